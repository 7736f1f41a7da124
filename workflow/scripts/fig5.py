"""Fig. 5: the same fragment for several k0/delta_k with amplitude histograms (thin)."""

from speckle.figures import static
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    fig5, source, seed = snakemake.params.fig5, snakemake.params.source, snakemake.params.seed
    ds = static.k0_sweep(
        fig5["k0_dk"],
        density=fig5["density"],
        n_alines=fig5["n_alines"],
        seed=seed,
        bins=fig5["bins"],
        **static.source_options(source),
        normalise=fig5["normalise"],
        dask=static.dask_options(snakemake.config["dask"], snakemake.threads),
        progress=True,
    )
    ds.attrs.update(provenance_attrs(config={"fig5": fig5, "source": source}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(static.plot_k0_fragments(ds, fig5["fragment"]), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
