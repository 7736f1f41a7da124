"""Elastography failure (thin): compute with speckle.figures.elastography on the config's Dask
scheduler (points and seeds in parallel), write NetCDF and PNG."""

from speckle.figures import elastography
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    ds = elastography.failure_data(
        snakemake.params.elastography,
        snakemake.params.seed,
        dask=snakemake.config["dask"],
        threads=snakemake.threads,
        progress=True,
    )
    to_netcdf(ds, snakemake.output.data)
    save(elastography.plot_failure(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
