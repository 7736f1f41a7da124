"""Stack the decorrelation-scan rows into one dataset and draw it (thin)."""

from speckle.figures.deformation import plot_scan, scan_combine
from speckle.io import open_dataset, to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    ds = scan_combine([open_dataset(path) for path in snakemake.input.points])
    to_netcdf(ds, snakemake.output.data)
    save(plot_scan(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
