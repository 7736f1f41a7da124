"""Elastography sequence (thin): compute with speckle.figures.elastography, write NetCDF and PNG."""

from speckle.figures import elastography
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    ds = elastography.sequence_data(snakemake.params.elastography, snakemake.params.seed)
    to_netcdf(ds, snakemake.output.data)
    save(elastography.plot_sequence(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
