"""results/dynamics/phantom: angiography and dOCT contrasts of the phantom (thin)."""

from speckle.figures import dynamics
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg, seed = snakemake.params.dynamics, snakemake.params.seed
    ds = dynamics.phantom_data(cfg, seed)
    ds.attrs.update(provenance_attrs(config={"dynamics": cfg}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(dynamics.plot_phantom(ds), snakemake.output.figure)
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
