"""B-scans under the beam vs independent lines (thin): speckle.figures.beam, NetCDF + PNG."""

from speckle.figures import beam
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    params = snakemake.params
    ds = beam.bscans_data(params.source, params.beam, params.seed)
    to_netcdf(ds, snakemake.output.data)
    save(beam.plot_bscans(ds), snakemake.output.figure)
    for name in ("lateral", "axial"):
        for kind in ("complex", "intensity"):
            print(f"{name} {kind} measured:\n{ds[f'{name}_{kind}'].values.round(3)}")
            print(f"{name} {kind} theory:\n{ds[f'{name}_{kind}_theory'].values.round(3)}")
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
