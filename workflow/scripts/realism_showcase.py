"""results/realism/showcase: a layered phantom, pure model beside the system effects (thin)."""

from speckle.figures import realism
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, seed = snakemake.params.realism["showcase"], snakemake.params.seed
    ds = realism.showcase_dataset(cfg, seed)
    ds.attrs.update(provenance_attrs(config={"realism": {"showcase": cfg}}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(realism.plot_showcase(ds, cfg["dynamic_range_db"]), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
