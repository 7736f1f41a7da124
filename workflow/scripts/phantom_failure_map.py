"""results/phantom/failure_map.*: where the phantom fit fails, one seed per Dask task (thin)."""

from speckle.figures import phantom
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg = snakemake.params.failure_map
    ds = phantom.failure_map_data(cfg, snakemake.params.dask)
    ds.attrs.update(provenance_attrs(config={"failure_map": cfg}, seed=cfg["seed"]))
    to_netcdf(ds, snakemake.output.data)
    save(phantom.plot_failure_map(ds), snakemake.output.figure)
    print(f"success fraction (thickness x contrast):\n{ds['success'].values.round(2)}")
    print(f"wrote {', '.join(snakemake.output)}")


run(main)
