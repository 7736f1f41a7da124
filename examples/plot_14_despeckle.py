"""
Speckle suppression against a known truth
=========================================

A layered phantom (three layers of relative backscatter 1, 4 and 0.5) imaged once, and the
speckle-free image of the same scatterers (``speckle.imaging.speckle_free_image``, the
expected intensity ``E|A|²``), the truth any suppression method should approach. Beside the
single look: four frequency looks compounded (physical compounding, at the cost of axial
resolution), and two digital filters of the single look (a median filter in the log domain
and the Lee filter), each scaled to the truth's mean (sub-band looks carry a quarter of the
spectrum, so their gain differs). The title of each panel gives the speckle contrast inside
the middle layer (1 for developed speckle, 0 for the truth) and the PSNR against the truth
(dB images, ``speckle.analysis.psnr_db``). The pipeline compares every method on a phantom
with edges and points in ``results/despeckle/``.
"""

import matplotlib.pyplot as plt
import numpy as np

import speckle
import speckle.analysis as sa
from speckle.imaging import speckle_free_image

src = speckle.spectrum(128, 1024.0, k0_dk=10)
scene = speckle.random_scatterers(
    96, 16.0, n_pixels=128, depth_range=1024.0, seed=1, count="poisson"
)
tissue = speckle.layer_stack([0.0, 300.0, 640.0], backscatter=[1.0, 4.0, 0.5])
scene = speckle.backscatter(scene, tissue)
img = speckle.bscan(scene, src, method="finufft", tol=1e-9)
truth = speckle_free_image(scene, src).values

windows = sa.subband_apodizations(128, 4, apodization="rectangular", overlap=0.0)
images = {
    "single look": img.intensity.values,
    "4 frequency looks": sa.compound(sa.frequency_looks(img, windows), "intensity").values,
    "median 5x5 (log)": np.asarray(
        sa.despeckle(img.intensity, "median", {"size": 5}, domain="log")
    ),
    "Lee 7x7": np.asarray(sa.despeckle(img.intensity, "lee", {"size": 7})),
}
images = {k: v * truth.mean() / v.mean() for k, v in images.items()}  # same mean: a gain
layer = np.zeros(truth.shape, bool)
layer[44:76, :] = True  # inside the middle layer (300-640 µm), away from its edges

fig, axes = plt.subplots(1, 5, figsize=(10, 3), sharey=True, layout="constrained")
scale = float(truth.mean())


def level(intensity):
    """Intensity in dB relative to the truth's mean."""
    return 10 * np.log10(np.maximum(intensity, 1e-12) / scale)


axes[0].imshow(level(truth), cmap="gray", vmin=-20, vmax=10, aspect="auto", extent=[0, 96, 1024, 0])
axes[0].set_title("truth E|A|²\n(speckle-free)", fontsize=8)
for ax, (name, intensity) in zip(axes[1:], images.items(), strict=True):
    ax.imshow(
        level(intensity), cmap="gray", vmin=-20, vmax=10, aspect="auto", extent=[0, 96, 1024, 0]
    )
    contrast = float(intensity[layer].std() / intensity[layer].mean())
    psnr = sa.psnr_db(level(intensity), level(truth))
    ax.set_title(f"{name}\nC = {contrast:.2f}, PSNR {psnr:.1f} dB", fontsize=8)
for ax in axes:
    ax.set_xlabel("A-line")
axes[0].set_ylabel("depth (µm)")
