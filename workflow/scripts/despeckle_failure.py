"""results/despeckle/failure: each family against density, SNR and feature size (thin)."""

from speckle.figures import despeckle
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, seed = snakemake.params.despeckle, snakemake.params.seed
    ds = despeckle.failure_data(cfg, seed)
    ds.attrs.update(provenance_attrs(config={"despeckle": cfg}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(despeckle.plot_failure(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
