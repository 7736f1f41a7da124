"""results/synthoct/self_consistency.*: the challenge's check beside its published table (thin)."""

from pathlib import Path

from speckle.figures import synthoct
from speckle.io import atomic_path, to_netcdf
from speckle.pipeline.outputs import save
from speckle.pipeline.runner import run
from speckle.provenance import provenance_attrs


def main(snakemake) -> None:
    cfg = snakemake.params.synthoct
    scans = {Path(p).stem.removeprefix("Scan_"): p for p in snakemake.input.scans} or None
    ds = synthoct.self_consistency_data(cfg, scans)
    ds.attrs.update(provenance_attrs(config={"synthoct": cfg}))
    to_netcdf(ds, snakemake.output.data)
    with atomic_path(snakemake.output.table) as tmp:
        Path(tmp).write_text(synthoct.table_csv(ds))
    save(synthoct.plot_self_consistency(ds), snakemake.output.figure)
    print(f"origins: {ds['origin'].values.tolist()}")
    for key, value in ds.attrs.items():
        if key.startswith("max_abs_deviation"):
            print(f"{key} = {value:.3g}")
    print(f"wrote {', '.join(snakemake.output)}")


run(main)
