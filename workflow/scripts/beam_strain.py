"""Correlation vs strain under the beam (thin): speckle.figures.beam, NetCDF + PNG."""

from speckle.figures import beam
from speckle.figures._style import log_to
from speckle.io import to_netcdf

with log_to(snakemake.log[0]):
    params = snakemake.params
    ds = beam.strain_data(params.source, params.beam, params.seed)
    to_netcdf(ds, snakemake.output.data)
    beam.strain_figure(ds, snakemake.output.figure)
    print(ds.to_dataframe().round(4).to_string())
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")
