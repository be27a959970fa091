"""Sweep the classifier's rotor speed and plot its grade curves (fines share per class).

    python python/examples/classifier_rpm.py [--out classifier-rpm.png] [--duration 0.1]

cases/classifier.toml (the paper's Section 5 classifier: four classes 100-280 µm fed at
the top, fines drained through the nozzle) with SCG α = 2 (8× fewer particles), run at
three rotor speeds. Each point is the share of a class's fed particles drained as fines
by the end, with its 95 % Wilson interval. CI runs it (about a minute on 2 cores).
"""

from __future__ import annotations

import argparse
import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import scg


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The 95 % Wilson score interval of a share k/n."""
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="classifier-rpm.png")
    ap.add_argument("--duration", type=float, default=0.1)
    ap.add_argument("--rpm", type=float, nargs="+", default=[2000.0, 3500.0, 5000.0])
    a = ap.parse_args()

    base = scg.Scene.load(
        "cases/classifier.toml",
        # dt resolves the SCG particles' contacts (≥ 20 steps each, as `scg check` asks)
        set={"duration": a.duration, "dt": 2.3e-7, "coarse_grain.alpha": 2},
    )
    table = scg.sweep(base, {"flow.rpm": a.rpm}, progress=True)
    diameters = {g["name"]: g["diameter"] for g in base.get("groups")}

    fig, ax = plt.subplots(figsize=(6, 4))
    for rpm, rows in table.groupby("flow.rpm"):
        counts = rows.pivot_table(index="group", columns="fate", values="count", aggfunc="sum")
        names = sorted(counts.index, key=lambda g: diameters[g])
        d = [diameters[g] * 1e6 for g in names]
        k = [int(counts.loc[g, "drained"]) for g in names]
        n = [int(counts.loc[g, "entered"]) for g in names]
        share = [ki / ni if ni else float("nan") for ki, ni in zip(k, n)]
        lo, hi = zip(*(wilson(ki, ni) for ki, ni in zip(k, n)))
        err = [[s - l for s, l in zip(share, lo)], [h - s for s, h in zip(share, hi)]]
        ax.errorbar(d, share, yerr=err, marker="o", capsize=3, label=f"{rpm:.0f} rpm")
        for g, ki, ni in zip(names, k, n):
            print(f"{rpm:6.0f} rpm  {g:>5}: {ki:5d} of {ni:5d} drained")
    ax.set_xlabel("original diameter [µm]")
    ax.set_ylabel("share drained as fines")
    ax.set_title(f"classifier, SCG α = 2, first {a.duration:g} s (95 % intervals)")
    ax.set_ylim(-0.02, 1.02)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=120)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
