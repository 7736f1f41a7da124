"""Fig. 6a (thin): compute with speckle.figures.deformation, write NetCDF and PNG."""

from speckle.figures import deformation
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    params = snakemake.params
    ds = deformation.fig6a_data(params.source, params.fig6, params.seed)
    to_netcdf(ds, snakemake.output.data)
    save(deformation.plot_fig6a(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
