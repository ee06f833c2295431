#!/usr/bin/env python3
"""The bending evaluated every j steps (solvers.mechanics.bending_subcycles)
on one degree of freedom: the figures of docs/mechanics-method.md, "Bending
evaluated less often than the membrane".

Model: mass 1, step 1, central differences; a slow spring kb (the bending,
evaluated at the first step of each window of j steps) and a fast spring kf
(the membrane or the contact, every step). The window's momentum is always
j f_b (f_b = -kb x at the window's first step); it is delivered
- as an impulse: j f_b at the first step;
- with a held part h (shell_rf_t3 from 0.10.0): h += alpha (f_b - h) at
  the window's first step, then h at every step of the window and
  j (f_b - h) at its first.

1. Amplification per window of a slow mode alone (kf = 0), from the
   window's transfer matrix, for a bending phase w = omega j dt per window:
   the impulse form is exactly 1; the held part adds a growth of about
   0.22 min(w, alpha)^2 at j = 8.
2. A constant force pressed on a stiff one-sided spring (a node held on a
   tool by the contact), with a little damping: the power the bending's
   delivery feeds into the node's vibration, per step (0 for a force
   applied at every step).

Usage: scripts/bench/subcycle_stability.py   (numpy)
"""
import numpy as np


def window_matrix(j, kf, kb, alpha):
    """Transfer matrix over one window of (x, v, h); alpha = 0: impulses."""
    m = np.zeros((3, 3))
    for col in range(3):
        x, v, h = np.eye(3)[col]
        f = -kb * x
        h = h + alpha * (f - h) if alpha > 0 else 0.0
        for i in range(j):
            fa = h + (j * (f - h) if i == 0 else 0.0)
            v = v + (-kf * x + fa)
            x = x + v
        m[:, col] = [x, v, h]
    return m


def growth(j, kf, kb, alpha):
    return max(abs(np.linalg.eigvals(window_matrix(j, kf, kb, alpha)))) - 1.0


def fed_power(scheme, j, wdt, damping=1e-3, steps=40000, alpha=1.0 / 64.0):
    """Mean power per step the bending's delivery does on a node pressed by
    a constant force 1 on a one-sided spring of frequency wdt per step
    (second half of the run)."""
    kc = wdt * wdt
    x, v, h, work = 1.0 / kc, 0.0, 0.0, 0.0
    for n in range(steps):
        if scheme == "every step":
            fa = 1.0
        elif n % j == 0:
            if scheme == "held part":
                h += alpha * (1.0 - h)
            fa = h + j * (1.0 - h)
        else:
            fa = h
        fc = -kc * x if x > 0 else 0.0
        vn = v + (fa + fc - damping * v)
        if n > steps // 2:
            work += fa * 0.5 * (v + vn)
        v, x = vn, x + vn
    return work / (steps - steps // 2)


def main():
    print("1. growth per window of a slow mode alone (kf = 0), j = 8; columns: phase w per window")
    phases = (0.003, 0.01, 0.03, 0.1, 0.3, 0.6, 1.0, 1.6)
    print("   alpha      " + " ".join("%8.3f" % w for w in phases))
    for alpha in (0.0, 1 / 256, 1 / 64, 1 / 32, 1 / 16, 1 / 4):
        name = "impulse" if alpha == 0 else "1/%d" % round(1 / alpha)
        print("   %-9s  " % name + " ".join("%8.1e" % growth(8, 0.0, (w / 8) ** 2, alpha) for w in phases))
    print("2. power fed per step into a node held on a stiff spring (force 1, damping 1e-3 per step)")
    print("   omega dt   " + " ".join("%-22s" % s for s in ("every step", "impulse j=4 / 8", "held part j=4 / 8")))
    for wdt in (0.2, 0.5, 1.0, 1.5):
        row = ["%.2e" % fed_power("every step", 1, wdt)]
        for scheme in ("impulse", "held part"):
            row.append("%.2e / %.2e" % (fed_power(scheme, 4, wdt), fed_power(scheme, 8, wdt)))
        print("   %-9.1f  " % wdt + " ".join("%-22s" % r for r in row))


if __name__ == "__main__":
    main()
