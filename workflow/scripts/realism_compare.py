"""results/realism/: the measured image against the model, effect by effect (thin)."""

import logging

from speckle._workflow import run
from speckle.analysis.measured import load_measured
from speckle.figures import realism
from speckle.figures._style import save
from speckle.io import to_netcdf
from speckle.provenance import provenance_attrs

STEP_STATS = ("score", "ks_distance", "skewness", "excess_kurtosis")


def main(snakemake) -> None:
    cfg, seed = snakemake.params.realism, snakemake.params.seed
    meas_cfg = cfg["measured"]
    roi = air = None
    reason = ""
    if not meas_cfg["path"]:
        reason = "not configured (realism.measured.path is null)"
    elif not hasattr(snakemake.input, "measured"):
        reason = f"not found at {meas_cfg['path']}"
    else:
        path, scale = snakemake.input.measured, meas_cfg["scale"]
        roi = load_measured(path, scale=scale, roi=meas_cfg["roi"])
        if meas_cfg.get("air_rows"):
            air = load_measured(path, scale=scale, roi={"depth": meas_cfg["air_rows"]})
    if roi is None:
        logging.getLogger("realism").warning("measured image %s; drawing the model only", reason)
    ds = realism.realism_dataset(roi, air, cfg, seed, reason)
    ds.attrs.update(provenance_attrs(config={"realism": cfg}, seed=seed))
    to_netcdf(ds, snakemake.output.data)
    save(realism.plot_realism(ds), snakemake.output.figure)
    print(f"measured: {ds.attrs['measured']}")
    for k in [v for v in ds.data_vars if v.startswith("fit_")]:
        print(f"{k} = {float(ds[k]):.5g}")
    print(f"final (smallest sufficient) effects: {ds.attrs['final_effects']}")
    if "needed" in ds:
        for e in ds.effect.values:
            print(
                f"without {e}: score {float(ds.dropped_score.sel(effect=e)):.2f}, "
                f"KS {float(ds.dropped_ks_distance.sel(effect=e)):.4f}, "
                f"needed {bool(ds.needed.sel(effect=e))}"
            )
        for s in ds.step.values:
            c = {k: float(ds[f"cumulative_{k}"].sel(step=s)) for k in STEP_STATS}
            print(f"{s}: " + ", ".join(f"{k} {v:.4f}" for k, v in c.items()))
    print(f"wrote {snakemake.output.data} and {snakemake.output.figure}")


run(main)
