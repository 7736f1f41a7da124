"""
Fig. 4: a measured image against the model
==========================================

The statistics of a measured, log-compressed B-scan against fully developed speckle. The log
gain and offset of a scanner are unknown, so the comparison uses statistics free of them: the
standardised log-intensity histogram, its skewness and excess kurtosis. The pipeline compares
a measured PDMS B-scan that is not part of the repository; this example writes its own
stand-in (the model with an intensity floor 20 dB below the mean, log-compressed to 8 bits,
as an OCT engine stores it) and loads it with ``speckle.load_image`` as you would load your
scanner's ``.npy`` file. The pipeline target is ``results/fig4/fig4.png``.
"""

import tempfile
from pathlib import Path

import numpy as np

import speckle
from speckle.figures import histograms, static
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig4, source = config["fig4"], config["source"]
options = {"k0_dk": source["k0_dk"], "seed": config["seed"], **static.source_options(source)}

# a stand-in for a measured image: 64 rows x 256 A-lines, floor 0.01 <I>, 8-bit log scale
src = speckle.spectrum(64, 512.0, k0_dk=source["k0_dk"])
scene = speckle.random_scatterers(256, 4.0, n_pixels=64, depth_range=512.0, seed=7)
intensity = speckle.add_floor(speckle.bscan(scene, src).intensity, 0.01)
stored = speckle.log_compress(intensity / intensity.mean(), gain=21.85, offset=120.0)
with tempfile.TemporaryDirectory() as tmp:
    path = Path(tmp) / "my_bscan.npy"
    np.save(path, stored.values)
    image = speckle.load_image(path, kind="log", dims=("depth", "x"), pixel_size=8.0, pitch=8.0)

sim = histograms.simulated_panels(
    density=fig4["density"],
    n_alines=64,
    method=fig4["method"],
    floor=fig4["floor"],
    bins=fig4["bins"],
    intensity_max=fig4["intensity_max"],
    amplitude_max=fig4["amplitude_max"],
    **options,
)
ds = histograms.fig4_dataset(sim, image)
fig = histograms.plot_fig4(ds)
print(f"skewness {float(ds.measured_skewness):.3f} (developed speckle: -1.14)")
print(f"excess kurtosis {float(ds.measured_excess_kurtosis):.3f} (developed speckle: 2.4)")
