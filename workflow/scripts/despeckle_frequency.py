"""results/despeckle/frequency_compounding.nc: split spectrum vs its theory (thin)."""

from speckle.figures import despeckle
from speckle.io import to_netcdf
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, seed = snakemake.params.frequency, snakemake.params.seed
    ds = despeckle.frequency_compounding_data(cfg, seed)
    ds.attrs.update(
        provenance_attrs(config={"despeckle": {"frequency_compounding": cfg}}, seed=seed)
    )
    to_netcdf(ds, snakemake.output.data)
    print(f"wrote {snakemake.output.data}")


run(main)
