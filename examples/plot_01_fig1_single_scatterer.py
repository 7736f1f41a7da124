"""
Fig. 1: one scatterer, its pixels and spectral components
=========================================================

A single point scatterer at 0, 1 and 1.25 pixels, imaged by the model's N spectral components.
At a pixel centre the image is one pixel (a delta); between centres it spreads over the
neighbours. Left: the pixel amplitudes; right: the spectral components. k0/Δk = 0 is the
formal Fourier transform of the paper's Fig. 1, k0/Δk = 10 a real SD-OCT source. The pipeline
target is ``results/fig1/fig1.png``.
"""

from speckle.figures import static
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig1, source = config["fig1"], config["source"]

ds = static.single_scatterer(
    fig1["positions"], fig1["k0_dk"], n_pixels=fig1["n_pixels"], pixel_size=source["pixel_size"]
)
fig = static.plot_single_scatterer(ds)
print(abs(ds.ascan).sel(k0_dk=0.0).round(3).values[:, :4])
