"""results/synthoct/batch.*: candidate phantoms scanned and scored on Dask (thin)."""

from speckle.figures import synthoct
from speckle.io import to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg = snakemake.params.synthoct
    ds = synthoct.batch_data(cfg, snakemake.params.dask)
    ds.attrs.update(provenance_attrs(config={"synthoct": cfg}, seed=cfg["batch"]["seed"]))
    to_netcdf(ds, snakemake.output.data)
    save(synthoct.plot_batch(ds), snakemake.output.figure)
    best = ds["SSIM"].sel(map="OAC").argmax(dim=("boundary", "energy"))
    boundary, energy = (float(ds[k][best[k]]) for k in ("boundary", "energy"))
    print(f"{ds.attrs['n_phantoms']} phantoms; best OAC SSIM at {boundary:g} um, {energy:g} %")
    print(f"wrote {', '.join(snakemake.output)}")


run(main)
