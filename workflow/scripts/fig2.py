"""Fig. 2: 10x10-pixel speckle fragments for several densities (thin)."""

from speckle.figures import static
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    fig2, source, seed = snakemake.params.fig2, snakemake.params.source, snakemake.params.seed
    ds = static.density_sweep(
        fig2["densities"],
        k0_dk=source["k0_dk"],
        n_alines=fig2["n_alines"],
        seed=seed,
        **static.source_options(source),
        normalise=fig2["normalise"],
        dask=static.dask_options(snakemake.config["dask"], snakemake.threads),
        progress=True,
    )
    ds.attrs.update(provenance_attrs(config={"fig2": fig2, "source": source}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(static.plot_density_fragments(ds, fig2["fragment"]), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
