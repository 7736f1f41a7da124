"""Large elastography sequence (thin): simulate and process lazily on the config's Dask
scheduler with speckle.figures.elastography, streaming the NetCDF; draw the PNG from it."""

from speckle.figures import elastography
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.sweep import dask_scheduler


def main(snakemake) -> None:
    cfg = snakemake.params.elastography
    with dask_scheduler(**snakemake.config["dask"]):
        ds = elastography.sequence_large_data(cfg, snakemake.params.seed, snakemake.output.data)
    per_frame = float(cfg["sequence_large"]["strain"])
    save(elastography.plot_sequence_large(ds, per_frame), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
