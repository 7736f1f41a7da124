"""Fig. 3: amplitude histograms for a density sweep with one Rayleigh fit (thin)."""

from speckle.figures import histograms
from speckle.io import to_netcdf
from speckle.pipeline import adapters
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    fig3, source, seed = snakemake.params.fig3, snakemake.params.source, snakemake.params.seed
    ds = histograms.density_histograms(
        fig3["densities"],
        n_alines=fig3["n_alines"],
        k0_dk=source["k0_dk"],
        seed=seed,
        **adapters.source_options(source),
        normalise=fig3["normalise"],
        bins=fig3["bins"],
        amplitude_max=fig3["amplitude_max"],
        method=fig3["method"],
        dask=adapters.dask_options(snakemake.config["dask"], snakemake.threads),
        progress=True,
    )
    ds.attrs.update(provenance_attrs(config={"fig3": fig3, "source": source}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(histograms.plot_density_histograms(ds), snakemake.output.figure)
    for rho in ds.density.values:
        p = ds.sel(density=rho)
        print(
            f"density {rho:g}: C = {float(p.contrast):.4f} +- {float(p.contrast_se):.4f}, "
            f"theory {float(p.contrast_theory):.4f}, Rayleigh sigma {float(p.rayleigh_sigma):.2f}"
        )
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
