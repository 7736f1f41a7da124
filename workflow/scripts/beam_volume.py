"""3-D volume streamed by tiles to a chunked NetCDF file, and its orthogonal slices (thin).

Runs on the local threads scheduler with the rule's threads; the progress bar goes to the log.
"""

import time

import dask

from speckle.figures import beam
from speckle.io import open_dataset, stream_to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run


def main(snakemake) -> None:
    params, out = snakemake.params, snakemake.output
    with dask.config.set(num_workers=snakemake.threads):
        ds = beam.volume_data(params.source, params.beam, params.seed)
        t0 = time.perf_counter()
        stream_to_netcdf(ds, out.data)
        wall = time.perf_counter() - t0
        field = ds.field
        print(
            f"volume: wall {wall:.2f} s, {field.sizes['x'] * field.sizes['y']} lines, "
            f"{field.sizes['depth']} pixels, {field.data.npartitions} chunks"
        )
        with open_dataset(out.data, load=False) as written:
            save(beam.plot_volume(written), out.figure)
    print(f"wrote {out.data} and {out.figure}")


run(main)
