"""Correlation vs strain under the beam (thin): speckle.figures.beam, NetCDF + PNG."""

from speckle.figures import beam
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    params = snakemake.params
    ds = beam.strain_data(params.source, params.beam, params.seed)
    to_netcdf(ds, snakemake.output.data)
    save(beam.plot_strain(ds), snakemake.output.figure)
    print(ds.to_dataframe().round(4).to_string())
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
