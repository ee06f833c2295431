#!/usr/bin/env python3
"""PNG figures from a ThermoStamp output folder (thermostamp report DIR).

Writes into DIR/figures/:
  profile_<probe>.png  through-thickness temperature at several times
  crystallinity_profile_<probe>.png  through-thickness crystallinity at
                       several times, for a probe that records it
  probes_mean.png      mean temperature of every probe against time
  map_<part>.png       mean / top / bottom temperature of each ply on its
                       deformed shape (top view), last frame; a quarter
                       model is mirrored into the full part
  shear_<part>.png     shear angle of each ply (degrees), last frame
  fibre_strain_<part>.png  strain along the fibres (E11 of membrane_strain,
                       %) of each ply, last frame, where the frames have it
  conductance_<part>.png  the conductance of each face of each ply (tool
                       contact, ply/ply, air), last frame, where the
                       frames have the field conductance
  tool_gap_<part>.png  the gap between each ply and its tools (mm), last
                       frame, where the frames have the field tool_gap
  stability_<part>.png  the long-term stiffness of each ply's membrane law
                       (N/m, red below 0: unstable), last frame, where
                       the frames have the field membrane_stability
  thickness_<part>.png  the thickness at constant volume of each ply, as
                       its change (%) from the first frame's, last frame,
                       where the frames have the field thickness
  crystallinity_<part>.png  the relative crystallinity of each ply (its
                       mean and its smallest value through the
                       thickness), last frame, where the frames have the
                       field crystallinity
  below_threshold_<part>.png  when each place of each ply first had a
                       value, and had every value, below
                       output.temperature_threshold (s; grey: not by the
                       last frame), where the frames have the field
                       below_threshold_from
  tool_forces.png      force on each moving tool against its travel
                       (punch force against stroke), and heat per tool
  plies.png            each ply's mean temperature against time, in a
                       band from its coldest to its hottest value, and
                       with output.temperature_threshold its share below
                       it, the heat it has received from the tools, the
                       heat exchanges and the other plies (from 0.38.0),
                       and with crystallisation kinetics its
                       crystallinity; with the mechanics, the band of its
                       elements' shear angles and, with output.shear_angle_limit,
                       the share of its area sheared beyond the limit,
                       where a ply's law lost its stability the share
                       of its area that did, and (from 0.40.0) the band of
                       its elements' thickness at constant volume
  energy.png           energy audit against time
  grippers.png         with grippers (constraints of type gripper): each
                       gripper's force on the plies against time
  blank_<part>.png     each ply's cut pattern (thermostamp blank, when
                       DIR/blank/blank.json is there): the pattern in the
                       blank with its fibre marks, the blank's edge, and
                       the edge formed (its draw-in), seen from the side
                       the blank's normal points to
  nest_<part>.png      with blank --roll: each ply's patterns on the roll
                       (the layout of DIR/blank/<ply>_nest.dxf)
  parts_<part>.png     with blank --parts N (N up to 500): the batch's
                       patterns (DIR/blank/<ply>_parts.dxf)
  materials.png        the specific heat and the conductivity against the
                       temperature of every material whose values
                       follow it (rows, held beyond the first and the
                       last), as the run took them (summary.json; formed
                       from a mixture where the material has one)
  study.png            error against wall time when DIR holds a study.csv
                       (at the probes, of each ply's mean temperature and,
                       where the study has them, of each ply's largest
                       shear angle and mean crystallinity)

With --against OTHER (thermostamp report DIR --against OTHER), also the
two runs on the same axes, DIR solid and OTHER dashed, into
DIR/figures/against/:
  probes.png           every scalar probe quantity the two runs share,
                       against time
  profiles.png         the through-thickness temperature of every probe
                       they share, at the start, the middle and the end
                       of the shorter run
  tools.png            force on each tool along z and heat per tool,
                       against time
  plies.png            each ply's mean temperature, coldest value, mean
                       crystallinity and largest shear angle (either
                       sign), as the runs have
  energy.png           internal, kinetic and contact energy against time
"""
import csv
import json
import os
import sys

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
except ImportError as e:  # pragma: no cover
    sys.stderr.write("error: report: needs python3-matplotlib and python3-numpy (%s)\n" % e)
    sys.exit(3)



def save(fig, out, filename, dpi=120, tight=True):
    """Writes fig as out/filename, closes it and returns the path."""
    if tight:
        fig.tight_layout()
    name = os.path.join(out, filename)
    fig.savefig(name, dpi=dpi)
    plt.close(fig)
    return name

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
        if quantity not in ("temperature_profile", "crystallinity_profile"):
            continue
        crystal = quantity == "crystallinity_profile"
        times = sorted(set(r[0] for r in rows))
        pick = [times[int(round(i))] for i in np.linspace(0, len(times) - 1, min(8, len(times)))]
        fig, ax = plt.subplots(figsize=(5, 4))
        for t in pick:
            pts = sorted((r[1], r[2]) for r in rows if r[0] == t)
            z = np.array([p[0] for p in pts]) * 1e3
            v = np.array([p[1] for p in pts])
            ax.plot(v, z, marker="." if len(z) < 30 else None, label="t = %.3g s" % t)
        ax.set_xlabel("relative crystallinity" if crystal else "temperature (degC)")
        ax.set_ylabel("z from mid-plane (mm)")
        ax.set_title("through-thickness %s, probe %s" % ("crystallinity" if crystal else "profile", probe))
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        made.append(save(fig, out, "%sprofile_%s.png" % ("crystallinity_" if crystal else "", probe)))
    means = [(p, rows) for (p, q), rows in sorted(data.items()) if q == "temperature_mean"]
    if means:
        fig, ax = plt.subplots(figsize=(6, 4))
        for probe, rows in means:
            ax.plot([r[0] for r in rows], [r[2] for r in rows], label=probe)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("mean temperature (degC)")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        made.append(save(fig, out, "probes_mean.png"))
    return made


def mirrored(xy, tri, values, per_element):
    """Mirror a quarter model (x >= 0, y >= 0 touching both axes) into four quadrants."""
    if xy[:, 0].min() < -1e-9 or xy[:, 1].min() < -1e-9 or xy[:, 0].min() > 1e-6 or xy[:, 1].min() > 1e-6:
        return [(xy, tri, values)]
    out = []
    for sx, sy in ((1, 1), (-1, 1), (1, -1), (-1, -1)):
        m = xy.copy()
        m[:, 0] *= sx
        m[:, 1] *= sy
        t = tri if sx * sy > 0 else tri[:, ::-1]
        out.append((m, t, values))
    return out


def finish_map(fig, ax, pc, title, label):
    """Title, axes in mm and colour bar of one ply's map."""
    ax.set_aspect("equal")
    ax.set_title(title, fontsize=9)
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    fig.colorbar(pc, ax=ax, label=label, shrink=0.8)


def shear_map(out, part, time, tri, xyz, vals):
    """The shear angle of one ply (per element, degrees)."""
    lim = max(abs(vals.min()), abs(vals.max()), 1e-9)
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    copies = mirrored(xyz[:, :2], tri, vals, True)
    for k, (mxy, mtri, v) in enumerate(copies):
        # mirroring about one axis reverses the sign of the shear angle
        sign = 1.0 if k in (0, 3) or len(copies) == 1 else -1.0
        pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, facecolors=sign * v, vmin=-lim, vmax=lim,
                          cmap="coolwarm")
    finish_map(fig, ax, pc, "%s: shear angle, t = %.3g s\nmin %.1f, max %.1f deg" % (part, time, vals.min(), vals.max()),
               "degrees")
    return save(fig, out, "shear_%s.png" % part, dpi=110, tight=False)


def fibre_strain_map(out, part, time, tri, xyz, vals):
    """E11 of one ply (per element, in %): the strain along the initial fibre
    direction; negative (blue) where the fibres are compressed."""
    lim = max(abs(vals.min()), abs(vals.max()), 1e-12)
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    # E11 is the same seen in a mirror image (the fibres map onto themselves)
    for mxy, mtri, v in mirrored(xyz[:, :2], tri, vals, True):
        pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, facecolors=v, vmin=-lim, vmax=lim, cmap="coolwarm")
    finish_map(fig, ax, pc, "%s: fibre strain E11, t = %.3g s\nmin %.3g, max %.3g %%" % (part, time, vals.min(),
                                                                                       vals.max()), "%")
    return save(fig, out, "fibre_strain_%s.png" % part, dpi=110, tight=False)


def conductance_map(out, part, time, tri, xyz, bottom, top):
    """The conductance of each face of one ply (per node, W/(m^2 K)): where it
    exchanges heat with a tool, the air or the other ply, and how much."""
    vmax = max(bottom.max(), top.max(), 1e-9)
    fig, axes = plt.subplots(1, 2, figsize=(11.4, 4.4))
    fig.subplots_adjust(wspace=0.45)
    for ax, (face, vals) in zip(axes, (("bottom", bottom), ("top", top))):
        for mxy, mtri, v in mirrored(xyz[:, :2], tri, vals, False):
            pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, v, vmin=0, vmax=vmax, cmap="magma",
                              shading="gouraud")
        finish_map(fig, ax, pc, "%s: conductance of the %s face, t = %.3g s\nmax %.4g W/(m2 K)"
                   % (part, face, time, vals.max()), "W/(m2 K)")
    return save(fig, out, "conductance_%s.png" % part, dpi=110, tight=False)


def tool_gap_map(out, part, time, tri, xyz, gap):
    """The gap between one ply and its tools (per node, mm): 0 to 2 mm, where
    a formed ply lies on its tools (about 0) or bridges, wrinkles or has not
    reached them yet; gaps beyond 2 mm in the top colour."""
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    for mxy, mtri, v in mirrored(xyz[:, :2], tri, gap[tri].mean(axis=1), True):
        pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, facecolors=np.clip(v, 0.0, 2.0), vmin=0.0,
                          vmax=2.0, cmap="magma_r")
    finish_map(fig, ax, pc, "%s: gap to its tools, t = %.3g s\nlargest %.3g mm, smallest %.3g mm"
               % (part, time, gap.max(), gap.min()), "mm")
    return save(fig, out, "tool_gap_%s.png" % part, dpi=110, tight=False)


def threshold_map(out, part, time, tri, xyz, some, every, threshold):
    """When each place of one ply went below the temperature threshold (per
    node, s): a value of the node's thickness (left) and all of them (right);
    a triangle takes its last node's time, grey where a node had not by the
    last frame."""
    cmap = plt.get_cmap("viridis").copy()
    cmap.set_bad("lightgrey")
    fig, axes = plt.subplots(1, 2, figsize=(11.4, 4.4))
    fig.subplots_adjust(wspace=0.45)
    title = "below %g degC" % threshold if threshold is not None else "below the threshold"
    for ax, (what, vals) in zip(axes, (("a value " + title, some), ("every value " + title, every))):
        face = vals[tri].max(axis=1)  # NaN where a node has not gone below
        for mxy, mtri, v in mirrored(xyz[:, :2], tri, face, True):
            pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, facecolors=np.ma.masked_invalid(v), vmin=0.0,
                              vmax=max(time, 1e-12), cmap=cmap)
        done = np.count_nonzero(~np.isnan(vals))
        finish_map(fig, ax, pc, "%s: %s from (s)\n%d of %d nodes by t = %.3g s; grey: not yet"
                   % (part, what, done, vals.size, time), "s")
    return save(fig, out, "below_threshold_%s.png" % part, dpi=110, tight=False)


def crystallinity_map(out, part, time, tri, xyz, mean, layers):
    """The relative crystallinity of one ply (0: amorphous melt, 1: as
    crystalline as the matrix gets), per node: its mean through the
    thickness (left) and its smallest value through the thickness (right,
    where the thickness is resolved: the least crystallised layer)."""
    nodes = xyz.shape[0]
    panels = [("mean through the thickness", mean)]
    if layers is not None and layers.size > nodes and layers.size % nodes == 0:
        panels.append(("smallest through the thickness", layers.reshape(nodes, -1).min(axis=1)))
    fig, axes = plt.subplots(1, len(panels), figsize=(5.7 * len(panels), 4.4), squeeze=False)
    fig.subplots_adjust(wspace=0.45)
    for ax, (what, vals) in zip(axes[0], panels):
        for mxy, mtri, v in mirrored(xyz[:, :2], tri, vals, False):
            pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, v, shading="gouraud", vmin=0.0, vmax=1.0,
                              cmap="cividis")
        finish_map(fig, ax, pc, "%s: relative crystallinity, %s\nt = %.3g s, from %.3f to %.3f"
                   % (part, what, time, vals.min(), vals.max()), "1")
    return save(fig, out, "crystallinity_%s.png" % part, dpi=110, tight=False)


def pressure_map(out, part, time, tri, xyz, vals):
    """The contact pressure of one ply (per node, kPa, some above zero): a log
    scale over three decades (a holder's pressure can be 50 times the
    punch's), grey where a triangle has a node out of contact."""
    top = vals.max()
    face = vals[tri].min(axis=1)
    cmap = plt.get_cmap("viridis").copy()
    cmap.set_under("lightgrey")
    norm = matplotlib.colors.LogNorm(vmin=1e-3 * top, vmax=top)
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    for mxy, mtri, v in mirrored(xyz[:, :2], tri, np.where(face > 0, vals[tri].mean(axis=1), 0.0), True):
        pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, facecolors=np.maximum(v, 1e-6 * top), norm=norm,
                          cmap=cmap)
    finish_map(fig, ax, pc, "%s: contact pressure (larger face), t = %.3g s\nmax %.3g kPa; grey: no contact"
               % (part, time, top), "kPa")
    return save(fig, out, "pressure_%s.png" % part, dpi=110, tight=False)


def element_map(xyz, tri, values, cmap_name, **scale):
    """A map of one value per element on a ply's shape (top view, mm),
    mirrored as the ply is, grey where a value is NaN; scale: vmin and vmax,
    or norm. Returns the figure, its axes and the last drawn collection."""
    cmap = plt.get_cmap(cmap_name).copy()
    cmap.set_bad("lightgrey")
    fig, ax = plt.subplots(figsize=(5.2, 4.4))
    for mxy, mtri, v in mirrored(xyz[:, :2], tri, values, True):
        pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, facecolors=np.ma.masked_invalid(v), cmap=cmap,
                          **scale)
    return fig, ax, pc


def thickness_map(out, part, time, tri, xyz, h, h0):
    """The thickness at constant volume of one ply (per element): its change
    in % from the first frame's (the job's thickness), thicker in red (a
    sheared or compacted zone), thinner in blue (stretched across the
    fibres); grey where an element had collapsed."""
    change = 100.0 * (h / h0 - 1.0)
    finite = change[np.isfinite(change)]
    lim = max(np.abs(finite).max() if finite.size else 0.0, 1e-9)
    fig, ax, pc = element_map(xyz, tri, change, "coolwarm", vmin=-lim, vmax=lim)
    finish_map(fig, ax, pc, "%s: thickness at constant volume, t = %.3g s\n%.4g to %.4g mm (%+.1f to %+.1f %%)"
               % (part, time, 1e3 * np.nanmin(h), 1e3 * np.nanmax(h), finite.min() if finite.size else np.nan,
                  finite.max() if finite.size else np.nan), "% of the initial thickness")
    return save(fig, out, "thickness_%s.png" % part, dpi=110, tight=False)


def stability_map(out, part, time, tri, xyz, q):
    """The smallest long-term stiffness q of one ply's membrane law (per
    element, N/m): diverging about 0, red where q < 0, where the law has
    lost its stability (user guide, "Material stability"); grey where the
    element had none (collapsed)."""
    finite = q[np.isfinite(q)]
    span = max(np.abs(finite).max() if finite.size else 1.0, 1e-12)
    fig, ax, pc = element_map(xyz, tri, q, "RdBu",
                              norm=matplotlib.colors.TwoSlopeNorm(vcenter=0.0, vmin=-span, vmax=span))
    unstable = np.count_nonzero(finite < 0)
    finish_map(fig, ax, pc, "%s: long-term membrane stiffness q, t = %.3g s\n%d of %d elements below 0 (red), "
               "smallest %.3g N/m" % (part, time, unstable, q.size, finite.min() if finite.size else np.nan), "N/m")
    return save(fig, out, "stability_%s.png" % part, dpi=110, tight=False)


def blank_axes(normal):
    """In-plane axes of a flat blank, as thermostamp blank takes them for its
    DXF files: x and y for a blank normal to z; otherwise the global axis
    least aligned with the normal (turned to have its largest component
    positive), projected into the plane, and the normal times it."""
    n = np.asarray(normal, dtype=float)
    if abs(n[2]) >= 1 - 1e-9:
        return np.array([1.0, 0, 0]), np.array([0, 1.0, 0])
    if n[np.argmax(np.abs(n))] < 0:
        n = -n
    a = np.zeros(3)
    a[np.argmin(np.abs(n))] = 1
    e1 = a - a.dot(n) * n
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(n, e1)


def plot_blank(folder, out):
    """Each ply's cut pattern from DIR/blank (thermostamp blank)."""
    where = os.path.join(folder, "blank")
    info = json.load(open(os.path.join(where, "blank.json")))
    made = []
    for part, p in sorted(info["plies"].items()):
        rows = list(csv.DictReader(open(os.path.join(where, p["csv"]))))
        for n, r in enumerate(rows):
            if None in r.values() or None in r:
                raise ValueError("%s: row %d is incomplete (cut short?)" % (p["csv"], n + 2))
        e1, e2 = blank_axes(p["normal"]) if p.get("flat") else (np.array([1.0, 0, 0]), np.array([0, 1.0, 0]))
        fig, ax = plt.subplots(figsize=(5.4, 5.0))
        for kind, style in (("edge", "k-"), ("pattern", "r-")):
            outlines = {}
            for r in rows:
                if r["kind"] == kind:
                    outlines.setdefault(int(r["outline"]), []).append(r)
            for k, o in sorted(outlines.items()):
                for pos, st, label in (("blank", style, "the blank's edge" if kind == "edge" else "the pattern"),
                                       ("formed", "k:", "the edge formed (top view)")):
                    if kind == "pattern" and pos == "formed":
                        continue
                    xyz = np.array([[float(r["%s_%s_m" % (pos, c)]) for c in "xyz"] for r in o])
                    xyz = np.vstack([xyz, xyz[:1]])
                    u, v = 1e3 * xyz.dot(e1), 1e3 * xyz.dot(e2)
                    if kind == "pattern":
                        ax.fill(u, v, color="tab:red", alpha=0.15, lw=0)
                    ax.plot(u, v, st, lw=1.2 if pos == "blank" else 0.8, label=label if k == 0 else None)
        ends = [r for r in rows if r["kind"] == "fibre"]
        for k, (a, b) in enumerate(zip(ends[0::2], ends[1::2])):
            xyz = np.array([[float(r["blank_%s_m" % c]) for c in "xyz"] for r in (a, b)])
            ax.plot(1e3 * xyz.dot(e1), 1e3 * xyz.dot(e2), "-", color="tab:blue", lw=0.6,
                    label="the fibres (marks)" if k == 0 else None)
        ax.set_aspect("equal")
        ax.set_xlabel("mm")
        ax.set_ylabel("mm")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2)
        margin = info.get("margin_m", 0) or 0
        moved = "" if margin == 0 else ", moved %s by %g mm" % ("out" if margin > 0 else "in", abs(1e3 * margin))
        ax.set_title("%s: cut pattern, t = %.3g s\n%.1f %% of the blank (%.4g m^2 formed), "
                     "edge drawn in up to %.3g mm\ntrim: %s%s" % (part, info["time_s"], 100 * p["kept_share"],
                                                          p["kept_formed_area_m2"],
                                                          1e3 * p.get("edge_displacement_max_m", float("nan")),
                                                          ", ".join(info["trims"]), moved),
                     fontsize=8)
        made.append(save(fig, out, "blank_%s.png" % part, dpi=110))
        if p.get("nest"):
            made.append(plot_nest(where, part, p["nest"], out))
            batch = p["nest"].get("parts")
            if batch and batch["count"] <= 500:  # longer batches are the layout's lanes over and over
                made.append(plot_nest(where, part, p["nest"], out, batch))
    return made


def read_nest_dxf(path):
    """The roll's edges (LINEs) and the copies (closed POLYLINEs) of a layout
    that thermostamp blank --roll writes (DXF R12, mm)."""
    lines = open(path).read().split("\n")
    pairs = zip(lines[0::2], lines[1::2])
    lines_out, polys, entity, values, poly = [], [], None, {}, None
    for code, value in pairs:
        code = code.strip()
        if code == "0":
            if entity == "VERTEX" and poly is not None:
                poly.append((values["10"], values["20"]))
            elif entity == "LINE":
                lines_out.append(((values["10"], values["20"]), (values["11"], values["21"])))
            entity, values = value.strip(), {}
            if entity == "POLYLINE":
                poly = []
            elif entity == "SEQEND" and poly is not None:
                polys.append(poly)
                poly = None
        elif code in ("10", "20", "11", "21"):
            values[code] = float(value)
    return lines_out, polys


def plot_nest(where, part, n, out, batch=None):
    """A ply's patterns on the roll (thermostamp blank --roll): the layout
    of <ply>_nest.dxf, or with `batch` (blank --parts) the batch's patterns
    of <ply>_parts.dxf."""
    edges, polys = read_nest_dxf(os.path.join(where, batch["dxf"] if batch else n["dxf"]))
    length = 1e3 * (batch["roll_length_m"] if batch else n["drawn_length_m"])
    width = 1e3 * n["roll_width_m"]
    fig, ax = plt.subplots(figsize=(min(14, 2 + 8 * length / max(length, width)), 1.5 + 6 * width / max(length, width)))
    for (a, b), (c, d) in edges:
        ax.plot([a, c], [b, d], "k-", lw=1.5)
    for k, poly in enumerate(polys):
        poly = poly + poly[:1]
        ax.fill([q[0] for q in poly], [q[1] for q in poly], color="tab:red", alpha=0.15, lw=0)
        ax.plot([q[0] for q in poly], [q[1] for q in poly], "r-", lw=0.8, label="the pattern" if k == 0 else None)
    ax.set_aspect("equal")
    known = n.get("fibre_angle_deg") is not None
    ax.set_xlabel("along the roll (mm)" + ((", the weft's direction" if n.get("turned_90") else ", the fibres' direction")
                                           if known else ""))
    ax.set_ylabel("across (mm)")
    ax.grid(alpha=0.3)
    if batch:
        what = ("a batch of %d: %.4g m of the roll (%.4g m at %.4g mm of roll per pattern)"
                % (batch["count"], batch["roll_length_m"], batch["count"] * n["roll_length_per_pattern_m"],
                   1e3 * n["roll_length_per_pattern_m"]))
    elif n["lanes"] > 0:
        pairs = n.get("pairs_turned_180")
        what = ("%d lane%s%s, a %s every %.4g mm, %.4g mm of roll per pattern, %.1f %% of the roll used"
                % (n["lanes"], "" if n["lanes"] == 1 else "s", " of pairs (one turned by 180 deg)" if pairs else "",
                   "pair" if pairs else "pattern", 1e3 * n["pitch_m"], 1e3 * n["roll_length_per_pattern_m"],
                   100 * n["utilisation"]))
        if n.get("turned_90"):
            what = "turned by 90 deg, " + what
    else:
        what = "the pattern does not fit across the roll"
    ax.set_title("%s on a roll %g mm wide, %g mm apart\n%s" % (part, width, 1e3 * n["gap_m"], what), fontsize=8)
    return save(fig, out, ("parts_%s.png" if batch else "nest_%s.png") % part, dpi=100)


def threshold_of(folder, part):
    """The ply's output.temperature_threshold from summary.json, None if unknown."""
    try:
        for p in json.load(open(os.path.join(folder, "summary.json"))).get("parts", []):
            if p.get("name") == part:
                return p.get("temperature_threshold")
    except (OSError, ValueError):
        pass
    return None


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
                for mxy, mtri, vals in mirrored(xyz[:, :2], tri, g[n][()], False):
                    pc = ax.tripcolor(mxy[:, 0] * 1e3, mxy[:, 1] * 1e3, mtri, vals, shading="gouraud",
                                      vmin=vmin, vmax=vmax, cmap="inferno")
                ax.set_aspect("equal")
                ax.set_title("%s\n%s, t = %.3g s" % (part, n.replace("temperature_", ""), time), fontsize=9)
                ax.set_xlabel("x (mm)")
                ax.set_ylabel("y (mm)")
            fig.colorbar(pc, ax=axes[0].tolist(), label="degC", shrink=0.8)
            made.append(save(fig, out, "map_%s.png" % part, dpi=110, tight=False))
        for part in f["parts"]:
            g = last[part]
            tri = f["parts"][part]["triangles"][()]
            xyz = g["nodes"][()]
            if "shear_angle" in g:
                made.append(shear_map(out, part, time, tri, xyz, g["shear_angle"][()]))
            if "membrane_strain" in g:
                made.append(fibre_strain_map(out, part, time, tri, xyz, 100 * g["membrane_strain"][()][:, 0]))
            if "contact_pressure" in g and g["contact_pressure"][()].max() > 0:
                made.append(pressure_map(out, part, time, tri, xyz, g["contact_pressure"][()] * 1e-3))
            if "conductance_top" in g and "conductance_bottom" in g:
                made.append(conductance_map(out, part, time, tri, xyz, g["conductance_bottom"][()],
                                            g["conductance_top"][()]))
            if "tool_gap" in g:
                made.append(tool_gap_map(out, part, time, tri, xyz, 1e3 * g["tool_gap"][()]))
            if "membrane_stability" in g:
                made.append(stability_map(out, part, time, tri, xyz, g["membrane_stability"][()]))
            first = f["frames"][frames[0]][part]
            if "thickness" in g and "thickness" in first:
                made.append(thickness_map(out, part, time, tri, xyz, g["thickness"][()], first["thickness"][()]))
            if "below_threshold_from" in g and "all_below_threshold_from" in g:
                made.append(threshold_map(out, part, time, tri, xyz, g["below_threshold_from"][()],
                                          g["all_below_threshold_from"][()], threshold_of(folder, part)))
            if "crystallinity_mean" in g:
                made.append(crystallinity_map(out, part, time, tri, xyz, g["crystallinity_mean"][()],
                                              g["crystallinity"][()] if "crystallinity" in g else None))
    return made


def plot_tools(folder, out):
    rows = list(csv.DictReader(open(os.path.join(folder, "tools.csv"))))
    tools = sorted(set(r["tool"] for r in rows), key=[r["tool"] for r in rows].index)
    # A third panel for tools whose temperature follows a table (tools.csv
    # of 0.17.0 on has the column).
    def temps(name):
        return [float(r["temperature"]) for r in rows if r["tool"] == name and r.get("temperature") not in (None, "")]
    varying = [n for n in tools if len(set(temps(n))) > 1]
    fig, axes = plt.subplots(1, 4 if varying else 3, figsize=(20 if varying else 15, 4))
    a1, a4, a2 = axes[0], axes[1], axes[2]
    if varying:
        a3 = axes[3]
        for name in varying:
            a3.plot([float(r["time"]) for r in rows if r["tool"] == name], temps(name), label=name)
        a3.set_xlabel("time (s)")
        a3.set_ylabel("tool temperature (degC)")
        a3.set_title("temperature of the tools that follow a table")
        a3.grid(alpha=0.3)
        a3.legend(fontsize=8)
    for name in tools:
        rs = [r for r in rows if r["tool"] == name]
        u = np.array([[float(r["ux"]), float(r["uy"]), float(r["uz"])] for r in rs])
        f = np.array([[float(r["fx"]), float(r["fy"]), float(r["fz"])] for r in rs])
        t = np.array([float(r["time"]) for r in rs])
        # The travel from where the tool starts (a displacement table may
        # start away from zero), along the direction of its largest excursion.
        moved = u - u[0]
        reach = np.linalg.norm(moved, axis=1)
        if reach.max() > 1e-3:  # tools that travel (a force-controlled holder barely moves)
            d = moved[int(np.argmax(reach))] / reach.max()
            a1.plot(moved @ d * 1e3, -(f @ d), label=name)  # force resisting the motion
        # The force over time (the press force; a holder's force rows).
        a4.plot(t, np.linalg.norm(f, axis=1), label=name)
        a2.plot(t, [float(r["heat_J"]) for r in rs], label=name)
    mark_stop([a4, a2], stop_of(folder))
    mark_restart([a4, a2], restart_of(folder))
    a4.set_xlabel("time (s)")
    a4.set_ylabel("force of the plies on the tool (N)")
    a4.set_title("tool forces over time")
    a1.set_xlabel("tool travel (mm)")
    a1.set_ylabel("force resisting the tool's motion (N)")
    a1.set_title("tool force against travel")
    a2.set_xlabel("time (s)")
    a2.set_ylabel("heat given to the plies (J)")
    a2.set_title("heat exchanged with each tool")
    if not a1.lines:  # e.g. a run interrupted early
        a1.text(0.5, 0.5, "no tool has travelled 1 mm yet", ha="center", va="center", transform=a1.transAxes)
    for a in (a1, a4, a2):
        a.grid(alpha=0.3)
        if a.lines:
            a.legend(fontsize=8)
    return [save(fig, out, "tool_forces.png")]


def stop_of(folder):
    """(what, t): how and when a run that did not complete stopped ("failed" or
    "interrupted", summary.json's simulated time), or None."""
    try:
        s = json.load(open(os.path.join(folder, "summary.json")))
        if s.get("status") in ("failed", "interrupted") and isinstance(s.get("simulated_time_s"), (int, float)):
            return s["status"], float(s["simulated_time_s"])
    except (OSError, ValueError, AttributeError):
        pass
    return None


def restart_of(folder):
    """The time a restarted run continued from its checkpoint (summary.json's
    restarted_from_s), or None."""
    try:
        t = json.load(open(os.path.join(folder, "summary.json"))).get("restarted_from_s")
        return float(t) if isinstance(t, (int, float)) else None
    except (OSError, ValueError, AttributeError):
        return None


def mark_restart(axes, t):
    """A grey dotted line at the checkpoint a restarted run continued from:
    the rows before it are those of the run that wrote it."""
    if t is None:
        return
    for a in axes:
        a.axvline(t, color="grey", ls=":", lw=1, label="restarted from t = %.4g s" % t)


def mark_stop(axes, stop):
    """A red dashed line at the time a run failed or was interrupted, on axes of time."""
    if stop is None:
        return
    for a in axes:
        a.axvline(stop[1], color="red", ls="--", lw=1, label="%s at t = %.4g s" % stop)


def ply_rows(folder):
    """plies.csv by ply (in the file's order): time and the columns as float arrays."""
    rows = list(csv.DictReader(open(os.path.join(folder, "plies.csv"))))
    names = list(dict.fromkeys(r["ply"] for r in rows))
    return {n: {k: np.array([float(r[k]) for r in rows if r["ply"] == n]) for k in rows[0] if k != "ply"}
            for n in names}


def job_as_run(folder):
    """The run's job_as_run.json ({} where it cannot be read)."""
    try:
        doc = json.load(open(os.path.join(folder, "job_as_run.json")))
        return doc if isinstance(doc, dict) else {}
    except (OSError, ValueError):
        return {}


def by_ply(job, value):
    """An output setting given as one number or as numbers by material, as {ply: number}."""
    if value is None:
        return {}
    try:
        if isinstance(value, dict):
            return {p["name"]: value[p["material"]] for p in job["parts"] if p.get("material") in value}
        return {p["name"]: value for p in job["parts"]}
    except (KeyError, TypeError):
        return {}


def plot_plies(folder, out):
    plies = ply_rows(folder)
    if not plies:
        return []
    job = job_as_run(folder)
    output = job.get("output") if isinstance(job.get("output"), dict) else {}
    threshold = by_ply(job, output.get("temperature_threshold"))
    limit = by_ply(job, output.get("shear_angle_limit"))
    # one value for every ply: one line; otherwise a line per ply in its colour
    common_t = len(set(threshold.values())) == 1 and len(threshold) == len(plies)
    common_l = len(set(limit.values())) == 1 and len(limit) == len(plies)
    panels = []
    if all("temperature_mean" in v for v in plies.values()):
        panels.append("temperature")
        if all("fraction_below" in v for v in plies.values()):
            panels.append("below")
    # the heat each ply received, by source (the sources some ply has)
    sources = [(q, lab, ls) for q, lab, ls in (("heat_from_tools", "tools", "-"),
                                               ("heat_from_exchanges", "heat exchanges", "--"),
                                               ("heat_from_plies", "other plies", ":"))
               if any(q in v and np.nanmax(np.abs(v[q])) > 0 for v in plies.values())]
    if sources:
        panels.append("heat")
    if any("crystallinity_mean" in v and not np.all(np.isnan(v["crystallinity_mean"])) for v in plies.values()):
        panels.append("crystallinity")
    if all("shear_angle_max" in v for v in plies.values()):
        panels.append("shear")
        if all("fraction_over_shear_limit" in v for v in plies.values()):
            panels.append("over")
    # the thickness at constant volume (plies.csv of 0.40.0 on)
    if all("thickness_min" in v for v in plies.values()):
        panels.append("thickness")
    # the share whose long-term response is unstable, where some ply has one
    if any("fraction_unstable" in v and np.nanmax(v["fraction_unstable"]) > 0 for v in plies.values()):
        panels.append("unstable")
    if not panels:
        return []
    fig, axes = grid(len(panels), 5.0, 4.0, 2 if len(panels) == 4 else 3)
    stop, restart = stop_of(folder), restart_of(folder)
    for a, panel in zip(axes, panels):
        mark_stop([a], stop)
        mark_restart([a], restart)
        for k, (name, v) in enumerate(plies.items()):
            c = "C%d" % k
            if panel == "temperature":
                a.fill_between(v["time"], v["temperature_min"], v["temperature_max"], color=c, alpha=0.2, lw=0)
                a.plot(v["time"], v["temperature_mean"], color=c, label="%s: mean, band from coldest to hottest" % name)
            elif panel == "shear":
                a.fill_between(v["time"], v["shear_angle_min"], v["shear_angle_max"], color=c, alpha=0.2, lw=0)
                a.plot(v["time"], v["shear_angle_max"], color=c, lw=1, label="%s: band from smallest to largest" % name)
                a.plot(v["time"], v["shear_angle_min"], color=c, lw=1)
            elif panel == "below":
                a.plot(v["time"], 100 * v["fraction_below"], color=c, label=name)
            elif panel == "heat":
                for q, lab, ls in sources:
                    if q in v:
                        a.plot(v["time"], v[q], color=c, ls=ls, label="%s: from the %s" % (name, lab))
            elif panel == "crystallinity":
                if "crystallinity_mean" in v and not np.all(np.isnan(v["crystallinity_mean"])):
                    a.fill_between(v["time"], v["crystallinity_min"], v["crystallinity_max"], color=c, alpha=0.2,
                                   lw=0)
                    a.plot(v["time"], v["crystallinity_mean"], color=c,
                           label="%s: mean, band from smallest to largest" % name)
            elif panel == "unstable":
                if "fraction_unstable" in v:
                    a.plot(v["time"], 100 * v["fraction_unstable"], color=c, label=name)
            elif panel == "thickness":
                a.fill_between(v["time"], 1e3 * v["thickness_min"], 1e3 * v["thickness_max"], color=c, alpha=0.2,
                               lw=0)
                a.plot(v["time"], 1e3 * v["thickness_min"], color=c, lw=1, label="%s: band from thinnest to thickest"
                       % name)
                a.plot(v["time"], 1e3 * v["thickness_max"], color=c, lw=1)
            else:
                a.plot(v["time"], 100 * v["fraction_over_shear_limit"], color=c, label=name)
        if panel == "temperature":
            for k, name in enumerate(plies):
                if name in threshold and (not common_t or k == 0):
                    a.axhline(threshold[name], color="grey" if common_t else "C%d" % k, ls="--", lw=1,
                              label="threshold %g degC%s" % (threshold[name], "" if common_t else " (%s)" % name))
            a.set_ylabel("temperature (degC)")
            a.set_title("temperature of each ply")
        elif panel == "shear":
            for k, name in enumerate(plies):
                if name in limit and (not common_l or k == 0):
                    for y in (limit[name], -limit[name]):
                        a.axhline(y, color="grey" if common_l else "C%d" % k, ls="--", lw=1,
                                  label=None if y < 0 else "limit +-%g deg%s" % (
                                      limit[name], "" if common_l else " (%s)" % name))
            a.set_ylabel("shear angle (deg)")
            a.set_title("shear angle of each ply's elements")
        elif panel == "crystallinity":
            a.set_ylabel("relative crystallinity")
            a.set_title("crystallinity of each ply")
            a.set_ylim(-0.02, 1.02)
        elif panel == "below":
            a.set_ylabel("% of the ply's heat capacity")
            a.set_title("share below %s" % ("%g degC" % next(iter(threshold.values())) if common_t
                                             else "each ply's threshold"))
            a.set_ylim(-2, 102)
        elif panel == "heat":
            a.axhline(0, color="grey", lw=0.5)
            a.set_ylabel("heat received so far (J)")
            a.set_title("heat received by each ply, by source")
        elif panel == "unstable":
            a.set_ylabel("% of the ply's initial area")
            a.set_title("share whose long-term response is unstable")
            a.set_ylim(-2, 102)
        elif panel == "thickness":
            a.set_ylabel("thickness (mm)")
            a.set_title("thickness at constant volume of each ply's elements")
        else:
            a.set_ylabel("% of the ply's initial area")
            a.set_title("share sheared beyond %s" % ("+-%g deg" % next(iter(limit.values())) if common_l
                                                      else "each ply's limit"))
            a.set_ylim(bottom=0)
        a.set_xlabel("time (s)")
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    return [save(fig, out, "plies.png")]


def plot_energy(folder, out):
    rows = list(csv.DictReader(open(os.path.join(folder, "energy.csv"))))
    if not rows:
        return []
    t = [float(r["time"]) for r in rows]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4))
    for key in ("kinetic", "internal", "external_work", "damping", "contact"):
        if key in rows[0]:
            a1.plot(t, [float(r[key]) for r in rows], label=key)
    a1.set_xlabel("time (s)")
    a1.set_ylabel("energy (J)")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    # The half-step form is never negative (the product form of the balance
    # is, when nodes vibrate near the step's frequency limit).
    ke_key = "kinetic_half_step" if "kinetic_half_step" in rows[0] else "kinetic"
    ke = np.array([float(r[ke_key]) for r in rows])
    ie = np.array([float(r["internal"]) for r in rows])
    ratio = np.where(np.abs(ie) > 0, ke / np.where(ie == 0, 1, np.abs(ie)), np.nan)
    a2.semilogy(t, np.abs(ratio), label="kinetic / internal")
    a2.semilogy(t, [max(float(r["balance_error"]), 1e-16) for r in rows], label="balance error")
    a2.axhline(0.05, color="grey", ls="--", lw=1)
    mark_stop([a1, a2], stop_of(folder))
    mark_restart([a1, a2], restart_of(folder))
    a2.set_xlabel("time (s)")
    a2.legend(fontsize=8)
    a2.grid(alpha=0.3, which="both")
    return [save(fig, out, "energy.png")] + plot_grippers(folder, out, rows)


def plot_grippers(folder, out, rows):
    """Each gripper's force on the plies against time (its constraint's
    reaction columns of energy.csv; the grippers as summary.json names them)."""
    try:
        grippers = json.load(open(os.path.join(folder, "summary.json"))).get("grippers") or []
    except (OSError, ValueError, AttributeError):
        return []
    if not grippers:
        return []
    t = [float(r["time"]) for r in rows]
    fig, ax = plt.subplots(figsize=(7, 4))
    for g in grippers:
        c = g["constraint"].rsplit("/", 1)[-1]
        f = np.array([[float(r["reaction%s_%s" % (c, d)]) for d in "xyz"] for r in rows])
        label = g["name"] + (" (%s jaws)" % g["jaws"] if g.get("jaws") in ("rigid", "swivelling") else "")
        ax.plot(t, np.linalg.norm(f, axis=1), label=label)
    mark_stop([ax], stop_of(folder))
    mark_restart([ax], restart_of(folder))
    ax.set_xlabel("time (s)")
    ax.set_ylabel("force on the plies (N)")
    ax.set_title("gripper forces")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return [save(fig, out, "grippers.png")]


def plot_materials(folder, out):
    """The specific heat and conductivity of every material whose values follow the temperature (summary.json)."""
    summary = json.load(open(os.path.join(folder, "summary.json")))
    mats = summary.get("materials") if isinstance(summary, dict) else None
    if not isinstance(mats, dict):
        return []

    def rows(v):
        return v if isinstance(v, list) and v and isinstance(v[0], list) else None

    tabled = [(n, m) for n, m in mats.items() if isinstance(m, dict) and
              (rows(m.get("specific_heat_J_kg_K")) or rows(m.get("conductivity_W_m_K")))]
    if not tabled:
        return []
    fig, axes = grid(3 * len(tabled), most=3)
    for i, (name, m) in enumerate(tabled):
        c, k = m.get("specific_heat_J_kg_K"), m.get("conductivity_W_m_K")
        temps = [r[0] for t in (rows(c), rows(k)) if t for r in t]
        lo, hi = min(temps), max(temps)
        pad = max(0.1 * (hi - lo), 5.0)
        span = (lo - pad, hi + pad)
        mix = m.get("fibre_volume_fraction")
        title = name + (" (mixture, Vf %g)" % mix if mix is not None else "")

        def curve(ax, value, col, label, style):
            # rows: held beyond the first and the last, linear between them
            table = rows(value)
            if table:
                x = [span[0]] + [r[0] for r in table] + [span[1]]
                y = [table[0][col]] + [r[col] for r in table] + [table[-1][col]]
                ax.plot(x, y, style, label=label)
                ax.plot([r[0] for r in table], [r[col] for r in table], "o", ms=3, color=ax.lines[-1].get_color())
            elif isinstance(value, (int, float)) or (isinstance(value, list) and len(value) == 3):
                v = value if isinstance(value, (int, float)) else value[col - 1]
                ax.plot(span, [v, v], style, label=label + " (constant)")

        a_c, a_along, a_across = axes[3 * i:3 * i + 3]
        curve(a_c, c, 1, "c", "-")
        curve(a_along, k, 1, "k11", "-")
        curve(a_across, k, 2, "k22", "--")
        curve(a_across, k, 3, "k33", ":")
        for ax, what, unit in ((a_c, "specific heat", "c (J/(kg K))"),
                               (a_along, "conductivity along the fibres", "k (W/(m K))"),
                               (a_across, "conductivity across", "k (W/(m K))")):
            if ax.lines:
                finish(ax, title + ": " + what, "temperature (degC)", unit)
    return [save(fig, out, "materials.png")]


UNITS = {"temperature_mean": "degC", "displacement_x": "m", "displacement_y": "m", "displacement_z": "m",
         "shear_angle": "deg", "fibre_strain": "", "contact_pressure": "Pa", "conductance": "W/(m^2 K)"}


def grid(n, width=4.2, height=3.0, most=3):
    """A figure with n subplots on up to `most` columns; the axes in a list."""
    cols = min(most, max(n, 1))
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(width * cols, height * rows), squeeze=False)
    axes = list(axes.flat)
    for a in axes[n:]:
        a.set_visible(False)
    return fig, axes[:n]


def finish(ax, title, xlabel, ylabel, legend_size=7):
    """Title, axis labels, grid and legend of one of the paired plots."""
    ax.set_title(title, fontsize=9)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=legend_size)


def against(folder, other, out):
    """The figures of two runs on the same axes (folder solid, other dashed)."""
    runs = ((folder, "-", os.path.basename(os.path.normpath(folder))),
            (other, "--", os.path.basename(os.path.normpath(other))))
    made = []

    def both(name):
        return all(os.path.exists(os.path.join(d, name)) for d, _, _ in runs)

    def table(d, name):
        with open(os.path.join(d, name)) as f:
            return list(csv.DictReader(f))

    if both("probes.csv"):
        data = [read_probes(os.path.join(d, "probes.csv")) for d, _, _ in runs]
        shared = sorted(k for k in data[0] if k in data[1])
        scalars = [k for k in shared if k[1] != "temperature_profile"]
        if scalars:
            fig, axes = grid(len(scalars))
            for ax, key in zip(axes, scalars):
                for rows, (_, ls, lab) in zip((data[0][key], data[1][key]), runs):
                    if key[1] == "conductance":  # two rows a sample: the bottom face (z < 0) and the top face
                        for face, keep in (("bottom", lambda z: z < 0), ("top", lambda z: z > 0)):
                            sel = [r for r in rows if r[1] is not None and keep(r[1])]
                            ax.plot([r[0] for r in sel], [r[2] for r in sel], ls, label="%s, %s" % (lab, face))
                        continue
                    ax.plot([r[0] for r in rows], [r[2] for r in rows], ls, label=lab)
                unit = UNITS.get(key[1], "")
                finish(ax, "%s, %s" % key, "time (s)", key[1] + (" (%s)" % unit if unit else ""))
            made.append(save(fig, out, "probes.png"))
        profiles = [k for k in shared if k[1] == "temperature_profile"]
        if profiles:
            fig, axes = grid(len(profiles), 4.2, 3.6)
            for ax, key in zip(axes, profiles):
                times = [sorted(set(r[0] for r in d[key])) for d in data]
                end = min(times[0][-1], times[1][-1])
                for k, t in enumerate((0.0, end / 2, end)):
                    for d, ts, (_, ls, lab) in zip(data, times, runs):
                        near = min(ts, key=lambda x: abs(x - t))
                        pts = sorted((r[1], r[2]) for r in d[key] if r[0] == near)
                        ax.plot([p[1] for p in pts], [p[0] * 1e3 for p in pts], ls, color="C%d" % k,
                                marker="." if len(pts) < 30 else None, label="%s, t = %.3g s" % (lab, near))
                finish(ax, "profile, probe %s" % key[0], "temperature (degC)", "z from mid-plane (mm)", 6)
            made.append(save(fig, out, "profiles.png"))
    if both("tools.csv"):
        tabs = [table(d, "tools.csv") for d, _, _ in runs]
        names = [n for n in dict.fromkeys(r["tool"] for r in tabs[0]) if any(r["tool"] == n for r in tabs[1])]
        if names:
            fig, axes = grid(2 * len(names))
            for k, name in enumerate(names):
                for rows, (_, ls, lab) in zip(tabs, runs):
                    rs = [r for r in rows if r["tool"] == name]
                    t = [float(r["time"]) for r in rs]
                    axes[2 * k].plot(t, [float(r["fz"]) for r in rs], ls, label=lab)
                    axes[2 * k + 1].plot(t, [float(r["heat_J"]) for r in rs], ls, label=lab)
                finish(axes[2 * k], "%s: force on the tool along z" % name, "time (s)", "fz (N)")
                finish(axes[2 * k + 1], "%s: heat given to the plies" % name, "time (s)", "heat (J)")
            made.append(save(fig, out, "tools.png"))
    if both("plies.csv"):
        tabs = [ply_rows(d) for d, _, _ in runs]
        names = [n for n in tabs[0] if n in tabs[1]]
        # (title, y label, the value from a ply's columns) where both runs have the columns
        kinds = [(k, y, f) for k, y, f, col in (
            ("mean temperature", "temperature (degC)", lambda v: v["temperature_mean"], "temperature_mean"),
            ("coldest value", "temperature (degC)", lambda v: v["temperature_min"], "temperature_min"),
            ("mean crystallinity", "relative crystallinity", lambda v: v["crystallinity_mean"], "crystallinity_mean"),
            ("largest shear angle (either sign)", "|shear angle| (deg)",
             lambda v: np.maximum(np.abs(v["shear_angle_min"]), np.abs(v["shear_angle_max"])), "shear_angle_max"))
            if all(col in t[n] for t in tabs for n in names)]
        if names and kinds:
            fig, axes = grid(len(kinds) * len(names))
            for k, name in enumerate(names):
                for j, (title, ylabel, value) in enumerate(kinds):
                    ax = axes[len(kinds) * k + j]
                    for plies, (_, ls, lab) in zip(tabs, runs):
                        v = plies[name]
                        ax.plot(v["time"], value(v), ls, label=lab)
                    finish(ax, "%s: %s" % (name, title), "time (s)", ylabel)
            made.append(save(fig, out, "plies.png"))
    if both("energy.csv"):
        tabs = [table(d, "energy.csv") for d, _, _ in runs]
        keys = [k for k in ("internal", "kinetic_half_step", "contact") if all(t and k in t[0] for t in tabs)]
        if keys:
            fig, axes = grid(len(keys))
            for ax, key in zip(axes, keys):
                for rows, (_, ls, lab) in zip(tabs, runs):
                    ax.plot([float(r["time"]) for r in rows], [float(r[key]) for r in rows], ls, label=lab)
                finish(ax, key, "time (s)", "energy (J)")
            made.append(save(fig, out, "energy.png"))
    return made


def plot_study(folder, out):
    path = os.path.join(folder, "study.csv")
    rows = list(csv.DictReader(open(path)))
    var = [r for r in rows if r["label"] != "reference"]
    # The error of each ply's mean temperature (error_<ply>_mean_K), where the table has one.
    means = [c for c in (rows[0].keys() if rows else []) if c.startswith("error_") and c.endswith("_mean_K")]
    means = [c for c in means if any(r[c] for r in var)]
    # ... and of each ply's largest shear angle (error_<ply>_shear_deg), in a study with the mechanics.
    shears = [c for c in (rows[0].keys() if rows else []) if c.startswith("error_") and c.endswith("_shear_deg")]
    shears = [c for c in shears if any(r[c] for r in var)]
    # ... and of each ply's mean crystallinity (error_<ply>_crystallinity), with crystallisation kinetics.
    crystal = [c for c in (rows[0].keys() if rows else []) if c.startswith("error_") and c.endswith("_crystallinity")]
    crystal = [c for c in crystal if any(r[c] for r in var)]
    n = 1 + bool(means) + bool(shears) + bool(crystal)
    cols = 2 if n == 4 else n  # four panels in two rows
    fig, grid_axes = plt.subplots(n // cols, cols, figsize=(5.5 * cols, 4.5 * (n // cols)), squeeze=False)
    axes = [list(grid_axes.flat)]
    ax = axes[0][0]
    for r in var:
        t, e = float(r["wall_time_s"]), max(float(r["error_K"]), 1e-6)
        ax.loglog([t], [e], "o")
        ax.annotate(r["label"], (t, e), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_ylabel("error against reference (K, %s norm)" % (var[0]["norm"] if var else "max"))
    ax.set_title("at the probes")
    # each ply's error of one quantity (columns error_<ply><suffix>) against wall time
    def per_ply(a, columns, suffix, ylabel, title):
        for k, c in enumerate(columns):
            pts = [(float(r["wall_time_s"]), max(float(r[c]), 1e-6), r["label"]) for r in var if r[c]]
            a.loglog([p[0] for p in pts], [p[1] for p in pts], "o", color="C%d" % k,
                     label=c[len("error_"):-len(suffix)])
            for t, e, label in pts:
                a.annotate(label, (t, e), textcoords="offset points", xytext=(4, 4), fontsize=7)
        a.set_ylabel(ylabel)
        a.set_title(title)

    if means:
        per_ply(axes[0][1], means, "_mean_K", "error of the ply's mean temperature (K)", "each ply's mean")
    if shears:
        per_ply(axes[0][1 + bool(means)], shears, "_shear_deg", "error of the ply's largest shear angle (deg)",
                "each ply's largest shear angle")
    if crystal:
        per_ply(axes[0][n - 1], crystal, "_crystallinity", "error of the ply's mean relative crystallinity",
                "each ply's mean crystallinity")
    ref = [r for r in rows if r["label"] == "reference"]
    for a in axes[0]:
        if ref and float(ref[0]["wall_time_s"]) > 0:  # an analytic reference takes no time
            a.axvline(float(ref[0]["wall_time_s"]), color="grey", ls="--", lw=1, label="reference run time")
        a.set_xlabel("wall time (s)")
        lo, hi = a.get_xlim()
        if 0 < lo and hi < 10 * lo:  # within a decade: plain numbers (the log labels would crowd)
            a.xaxis.set_major_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
            a.xaxis.set_minor_formatter(matplotlib.ticker.FormatStrFormatter("%g"))
        a.grid(alpha=0.3, which="both")
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=8)
    fig.tight_layout()
    # study.png also lands next to study.csv, as the contract says
    fig.savefig(os.path.join(folder, "study.png"), dpi=120)
    return [save(fig, out, "study.png", tight=False)]


def main():
    args = sys.argv[1:]
    other = None
    if len(args) == 3 and args[1] == "--against":
        other = args[2]
        args = args[:1]
    if len(args) != 1:
        sys.stderr.write("usage: report.py DIR [--against OTHER]\n")
        return 2
    folder = args[0]
    out = os.path.join(folder, "figures")
    os.makedirs(out, exist_ok=True)
    made, failed = [], 0
    # Each file's figures on their own: a file that cannot be read (a run
    # killed while writing it, a file edited by hand) is named in one line,
    # and the figures of the others are still made.
    for name, plot in (("study.csv", plot_study), ("probes.csv", plot_probes), ("results.h5", plot_maps),
                       ("tools.csv", plot_tools), ("plies.csv", plot_plies), ("energy.csv", plot_energy),
                       ("summary.json", plot_materials), (os.path.join("blank", "blank.json"), plot_blank)):
        if not os.path.exists(os.path.join(folder, name)):
            continue
        try:
            made += plot(folder, out)
        except Exception as e:  # noqa: BLE001 (any reader or plotting error)
            failed += 1
            reason = "no column %s" % e if isinstance(e, KeyError) else " ".join(str(e).split()) or type(e).__name__
            sys.stderr.write("error: report: cannot plot %s: %s\n" % (os.path.join(folder, name), reason))
        finally:
            plt.close("all")
    if other is not None:
        apart = os.path.join(out, "against")
        os.makedirs(apart, exist_ok=True)
        try:
            pair = against(folder, other, apart)
        except Exception as e:  # noqa: BLE001 (any reader or plotting error)
            pair = []
            failed += 1
            sys.stderr.write("error: report: cannot plot %s against %s: %s\n"
                             % (folder, other, " ".join(str(e).split()) or type(e).__name__))
        finally:
            plt.close("all")
        if not pair and not failed:
            failed += 1
            sys.stderr.write("error: report: %s and %s share no probe, tool, ply or energy history\n" % (folder, other))
        made += pair
    for m in made:
        print(m)
    stop = stop_of(folder)
    if made and stop is not None:
        print("the run %s at t = %.6g s: the figures over time mark it (red dashed line)"
              % ("failed" if stop[0] == "failed" else "was interrupted", stop[1]))
    restart = restart_of(folder)
    if made and restart is not None:
        print("the run continued from its checkpoint at t = %.6g s: the figures over time mark it (grey dotted line)"
              % restart)
    if not made and not failed:
        sys.stderr.write("error: report: nothing to plot in %s (no study.csv, probes.csv, results.h5, tools.csv, "
                         "plies.csv or energy.csv)\n" % folder)
        return 3
    return 3 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
