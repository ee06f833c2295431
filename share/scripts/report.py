#!/usr/bin/env python3
"""PNG figures from a ThermoStamp output folder (thermostamp report DIR).

Writes into DIR/figures/:
  profile_<probe>.png  through-thickness temperature at several times
  probes_mean.png      mean temperature of every probe against time
  map_<part>.png       mean / top / bottom temperature of each ply, last frame
  study.png            error against wall time when DIR holds a study.csv
"""
import csv
import os
import sys

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
except ImportError as e:  # pragma: no cover
    sys.stderr.write("report: needs python3-matplotlib and python3-numpy (%s)\n" % e)
    sys.exit(3)


def read_probes(path):
    data = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            key = (row["probe"], row["quantity"])
            z = float(row["z"]) if row["z"] else None
            data.setdefault(key, []).append((float(row["time"]), z, float(row["value"])))
    return data


def plot_probes(folder, out):
    data = read_probes(os.path.join(folder, "probes.csv"))
    made = []
    for (probe, quantity), rows in sorted(data.items()):
        if quantity != "temperature_profile":
            continue
        times = sorted(set(r[0] for r in rows))
        pick = [times[int(round(i))] for i in np.linspace(0, len(times) - 1, min(8, len(times)))]
        fig, ax = plt.subplots(figsize=(5, 4))
        for t in pick:
            pts = sorted((r[1], r[2]) for r in rows if r[0] == t)
            z = np.array([p[0] for p in pts]) * 1e3
            v = np.array([p[1] for p in pts])
            ax.plot(v, z, marker="." if len(z) < 30 else None, label="t = %.3g s" % t)
        ax.set_xlabel("temperature (degC)")
        ax.set_ylabel("z from mid-plane (mm)")
        ax.set_title("through-thickness profile, probe %s" % probe)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        name = os.path.join(out, "profile_%s.png" % probe)
        fig.savefig(name, dpi=120)
        plt.close(fig)
        made.append(name)
    means = [(p, rows) for (p, q), rows in sorted(data.items()) if q == "temperature_mean"]
    if means:
        fig, ax = plt.subplots(figsize=(6, 4))
        for probe, rows in means:
            ax.plot([r[0] for r in rows], [r[2] for r in rows], label=probe)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("mean temperature (degC)")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        name = os.path.join(out, "probes_mean.png")
        fig.savefig(name, dpi=120)
        plt.close(fig)
        made.append(name)
    return made


def plot_maps(folder, out):
    try:
        import h5py
    except ImportError:
        sys.stderr.write("report: python3-h5py missing, no temperature maps\n")
        return []
    made = []
    with h5py.File(os.path.join(folder, "results.h5"), "r") as f:
        frames = sorted(f["frames"].keys())
        if not frames:
            return []
        last = f["frames"][frames[-1]]
        time = last.attrs["time"]
        for part in f["parts"]:
            tri = f["parts"][part]["triangles"][()]
            g = last[part]
            xyz = g["nodes"][()]
            fields = [n for n in ("temperature_top", "temperature_mean", "temperature_bottom") if n in g]
            if not fields:
                continue
            vmin = min(g[n][()].min() for n in fields)
            vmax = max(g[n][()].max() for n in fields)
            fig, axes = plt.subplots(1, len(fields), figsize=(4.2 * len(fields), 3.8), squeeze=False)
            for ax, n in zip(axes[0], fields):
                pc = ax.tripcolor(xyz[:, 0] * 1e3, xyz[:, 1] * 1e3, tri, g[n][()], shading="gouraud",
                                  vmin=vmin, vmax=vmax, cmap="inferno")
                ax.set_aspect("equal")
                ax.set_title("%s\n%s, t = %.3g s" % (part, n.replace("temperature_", ""), time), fontsize=9)
                ax.set_xlabel("x (mm)")
                ax.set_ylabel("y (mm)")
            fig.colorbar(pc, ax=axes[0].tolist(), label="degC", shrink=0.8)
            name = os.path.join(out, "map_%s.png" % part)
            fig.savefig(name, dpi=110)
            plt.close(fig)
            made.append(name)
    return made


def plot_study(folder, out):
    path = os.path.join(folder, "study.csv")
    rows = list(csv.DictReader(open(path)))
    var = [r for r in rows if r["label"] != "reference"]
    fig, ax = plt.subplots(figsize=(6, 4.5))
    for r in var:
        t, e = float(r["wall_time_s"]), max(float(r["error_K"]), 1e-6)
        ax.loglog([t], [e], "o")
        ax.annotate(r["label"], (t, e), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ref = [r for r in rows if r["label"] == "reference"]
    if ref:
        ax.axvline(float(ref[0]["wall_time_s"]), color="grey", ls="--", lw=1, label="reference run time")
        ax.legend(fontsize=8)
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("error against reference (K, %s norm)" % (var[0]["norm"] if var else "max"))
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    name = os.path.join(out, "study.png")
    fig.savefig(name, dpi=120)
    # study.png also lands next to study.csv, as the contract says
    fig.savefig(os.path.join(folder, "study.png"), dpi=120)
    plt.close(fig)
    return [name]


def main():
    if len(sys.argv) != 2:
        sys.stderr.write("usage: report.py DIR\n")
        return 2
    folder = sys.argv[1]
    out = os.path.join(folder, "figures")
    os.makedirs(out, exist_ok=True)
    made = []
    if os.path.exists(os.path.join(folder, "study.csv")):
        made += plot_study(folder, out)
    if os.path.exists(os.path.join(folder, "probes.csv")):
        made += plot_probes(folder, out)
    if os.path.exists(os.path.join(folder, "results.h5")):
        made += plot_maps(folder, out)
    if not made:
        sys.stderr.write("report: nothing to plot in %s\n" % folder)
        return 3
    for m in made:
        print(m)
    return 0


if __name__ == "__main__":
    sys.exit(main())
