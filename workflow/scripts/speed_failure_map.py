"""Failure map of the synthesis methods (thin: config -> package -> files)."""

from speckle.figures.speed import plot_failure_map
from speckle.io import to_netcdf
from speckle.pipeline.adapters import dask_options
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs
from speckle.studies.speed import failure_map


def main(snakemake) -> None:
    cfg, source, seed = (
        snakemake.params.speed_accuracy,
        snakemake.params.source,
        snakemake.params.seed,
    )
    fm = cfg["failure_map"]
    ds = failure_map(
        fm["n_pixels"],
        fm["density"],
        fm["k0_dk"],
        base=fm["base"],
        n_lines=fm["n_lines"],
        pixel_size=source["pixel_size"],
        fwhm_fraction=cfg["fwhm_fraction"],
        seed=seed,
        dask=dask_options(snakemake.config["dask"], snakemake.threads),
    )
    ds.attrs.update(provenance_attrs(config={"speed_accuracy": cfg, "source": source}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(plot_failure_map(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
