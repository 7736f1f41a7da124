"""One row of the decorrelation scan (thin): speckle.figures.deformation.scan_point_data."""

from speckle.figures.deformation import scan_point_data
from speckle.io import to_netcdf
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    params = snakemake.params
    ds = scan_point_data(params.source, params.fig6, params.scan, params.seed, **params.point)
    to_netcdf(ds, snakemake.output[0])
    print(f"wrote {snakemake.output[0]}")


run(main)
