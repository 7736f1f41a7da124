"""
Fig. 5: the same scatterers at two k0/Δk
========================================

The same scatterers imaged with k0/Δk = 10 and 1: the speckle texture changes (scatterers in
a resolution cell interfere with the phase ``2 k0 z``), the amplitude statistics do not (both
histograms follow the same Rayleigh law). Reduced here to 16 A-lines; the pipeline target is
``results/fig5/fig5.png``.
"""

from speckle.figures import static
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig5, source = config["fig5"], config["source"]

ds = static.k0_sweep(
    fig5["k0_dk"],
    density=fig5["density"],
    n_alines=16,
    seed=config["seed"],
    bins=20,
    normalise=fig5["normalise"],
    **static.source_options(source),
)
fig = static.plot_k0_fragments(ds, fig5["fragment"])
print(ds.rayleigh_sigma.values.round(2))
