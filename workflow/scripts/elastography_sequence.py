"""Elastography sequence (thin): compute with speckle.figures.elastography, write NetCDF and PNG."""

from speckle.figures import elastography
from speckle.figures._style import log_to
from speckle.io import to_netcdf

with log_to(snakemake.log[0]):
    ds = elastography.sequence_data(snakemake.params.elastography, snakemake.params.seed)
    to_netcdf(ds, snakemake.output.data)
    elastography.sequence_figure(ds, snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")
