"""The SynthOCT processor's and orchestrator's quirks, each one's effect on the published data.

Run from the repository root (~1 min on 2 cores)::

    python benchmarks/synthoct_quirks.py

On the four published scans (``speckle/data/synthoct``) it prints the numbers of
``docs/explanation/synthoct_metrics.md``:

1. the maps: how many grey levels numpy's float32 power on this machine rounds differently
   from the correctly rounded one, and how many map pixels that moves; the OAC and SC of the
   40 dB (official) against the 51 dB (physical) linearisation; the OAC's bottom rows; the
   limits the SC/RSC PNGs really span after ``imsave``'s second stretch;
2. the metrics: each score with the truncation of the 8-bit read-back removed, with exact
   ``level/255`` instead of the luminance, and of the physical variant, as the largest change
   over the 12 rows of the published table.
"""

from __future__ import annotations

from importlib.resources import files
from pathlib import Path

import numpy as np

import speckle
from speckle.synthoct import maps as mp  # private: the quirks are switched off one by one
from speckle.synthoct import metrics as mt  # private: idem

DATA = Path(str(files("speckle.data") / "synthoct"))
SCANS = ("Exp1_Uniform_A", "Exp1_Uniform_B", "Exp2_Layers_A", "Exp2_Layers_B")
SCORED = ("SSIM", "MS-SSIM", "PSNR", "MSE", "VIF")


def grey(name: str) -> np.ndarray:
    return np.asarray(speckle.read_scan(DATA / f"Scan_{name}.png").values)


def maps_section() -> None:
    print("== maps ==")
    levels = np.arange(256)
    v = np.divide(levels, 255, dtype=np.float32)
    v = np.stack([v, v, v], -1).mean(-1)
    naive = 10.0 ** (v * 4.0)  # numpy's float32 power, as the processor calls it
    exact = mp._linear_table(40.0, True)
    print(f"float32 10**x: {np.count_nonzero(naive != exact)} of 256 levels differ here")
    moved, total = 0, 0
    for name in SCANS:
        g = grey(name)
        intensity = naive[g]
        oac = mp._oac(intensity, 6.0)
        images = {
            "OAC": mp._grey_levels(oac, np.min(oac), np.percentile(oac, 99), stretch=True),
            "SC": mp._grey_levels(mp._contrast(intensity, 20), 0.5, 5.0, stretch=True),
            "RSC": mp._grey_levels(mp._contrast(oac, 20), 0.5, 5.0, stretch=True),
        }
        ref = speckle.synthoct_maps(g, images=True)
        for k, im in images.items():
            moved += int(np.count_nonzero(im != ref[k].values))
            total += im.size
    print(f"  with numpy's power: {moved} of {total} map pixels move (by 1-2 grey levels)")
    for name in SCANS:
        g = grey(name)
        off = speckle.synthoct_maps(g)
        phy = speckle.synthoct_maps(g, variant="physical")
        rows = slice(80, 160) if "Layers" in name else slice(20, 200)
        ratio = float(off.OAC[rows].median() / phy.OAC[rows].median())
        mean = float(off.OAC[rows].mean() / phy.OAC[rows].mean())
        print(
            f"{name}: OAC rows {rows.start}-{rows.stop} official/physical: median {ratio:.3f}, "
            f"mean {mean:.3f} (40/51 = {40 / 51:.3f}); SC median "
            f"{float(off.SC.median()):.3f} official, {float(phy.SC.median()):.3f} physical"
        )
        mid = float(off.OAC[rows].median())
        bottom = off.OAC.median("x").values
        high = np.flatnonzero(bottom < 2 * mid)[-1] + 1
        p99 = float(np.percentile(off.OAC.values, 99))
        saturated = np.mean(off.OAC.values >= p99, axis=1)
        print(
            f"  OAC bottom row {float(off.OAC[-1].median()):.4f} /um (1/h = {1 / 6:.4f}); row "
            f"median above 2x the mid-depth one from row {high} of 256; PNG saturates at "
            f"{p99:.4f} /um, {saturated[-10:].mean():.0%} of the last 10 rows, "
            f"{saturated[:-10].mean():.2%} elsewhere"
        )
        for k in ("SC", "RSC"):
            values = off[k].values
            v = np.clip((values - 0.5) / (4.5 + 1e-10), 0, 1)
            lo, hi = 0.5 + 4.5 * float(v.min()), 0.5 + 4.5 * float(v.max())
            below = float(np.mean(values < 0.5))
            print(f"  {k} PNG spans {lo:.3f}..{hi:.3f} (stated 0.5..5; {below:.1%} below 0.5)")
    print(f"  levels never written by the gray colormap: {np.count_nonzero(mp._LUT != levels)}")


def metrics_section() -> None:
    print("== metrics (largest change over the 12 published rows) ==")
    exact = np.count_nonzero(mt._LUMINANCE != np.arange(256) / 255)
    lowered = np.count_nonzero(mt._TRUNCATED != np.arange(256))
    print(f"luminance != level/255 for {exact} levels; truncation lowers {lowered}")
    report = speckle.read_metrics_report(DATA / "Final_Metrics_Report.csv")
    official = {}
    for e, (a, b) in speckle.SYNTHOCT_EXPERIMENTS.items():
        official[e] = speckle.synthoct_metrics(grey(a), grey(b), lpips=False)
    dev = {m: max(float(np.abs(official[e][m] - report[m].sel(experiment=e)).max())
                  for e in official) for m in SCORED}  # fmt: skip
    print("official vs published: " + ", ".join(f"{m} {d:.1e}" for m, d in dev.items()))
    saved = (mt._LUMINANCE.copy(), mt._TRUNCATED.copy())
    for label, lum, trunc in (
        ("no truncation", saved[0], np.arange(256, dtype=np.uint8)),
        ("exact level/255", np.arange(256) / 255, saved[1]),
    ):
        mt._LUMINANCE[:], mt._TRUNCATED[:] = lum, trunc
        try:
            out = {e: speckle.synthoct_metrics(grey(a), grey(b), lpips=False)
                   for e, (a, b) in speckle.SYNTHOCT_EXPERIMENTS.items()}  # fmt: skip
        finally:
            mt._LUMINANCE[:], mt._TRUNCATED[:] = saved
        change = {m: max(float(np.abs(out[e][m] - official[e][m]).max()) for e in out)
                  for m in SCORED}  # fmt: skip
        print(f"{label}: " + ", ".join(f"{m} {d:.2g}" for m, d in change.items()))
    print("physical variant (51 dB, limits kept, exact levels):")
    for e, (a, b) in speckle.SYNTHOCT_EXPERIMENTS.items():
        phy = speckle.synthoct_metrics(grey(a), grey(b), variant="physical", lpips=False)
        for m in ("SSIM", "MS-SSIM", "VIF"):
            pairs = " ".join(
                f"{k}:{float(official[e][m].sel(map=k)):.3f}->{float(phy[m].sel(map=k)):.3f}"
                for k in ("OAC", "SC", "RSC")
            )
            print(f"  {e} {m}: {pairs}")


if __name__ == "__main__":
    maps_section()
    metrics_section()
