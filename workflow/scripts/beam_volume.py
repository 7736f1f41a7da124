"""3-D volume streamed by tiles to a chunked NetCDF file, and its orthogonal slices (thin).

Runs on the local threads scheduler with the rule's threads; the progress bar goes to the log.
"""

import dask

from speckle._workflow import run
from speckle.figures import beam


def main(snakemake) -> None:
    with dask.config.set(num_workers=snakemake.threads):
        params = snakemake.params
        facts = beam.write_volume(params.source, params.beam, params.seed, snakemake.output.data)
        print(f"volume: {facts}")
        beam.volume_figure(snakemake.output.data, snakemake.output.figure)
        print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
