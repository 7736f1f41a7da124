"""Bad configurations stop when the workflow loads, naming the key, before any job runs.

Each case of issue 13 is a small override layered over the CI config with ``--configfile``;
``snakemake -n`` must fail with the key path in its output and no job planned or run. The same
checks are exercised directly on :func:`speckle.pipeline.checks.check_config` (fast), and
the schema's method enum is compared with the package's method registry.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

import speckle
from speckle.pipeline.checks import check_config, check_scan_table
from speckle.pipeline.config_keys import rename_retired_keys

SCHEMA = "workflow/schemas/config.schema.yaml"
#: key path expected in the error, override (merged over the CI config).
BAD_CONFIGS = {
    "fig3.method": {"fig3": {"method": "fastest"}},
    "fig5.n_alines": {"fig5": {"n_alines": 16.0}},
    "fig2.fragment.depth": {"fig2": {"fragment": {"depth": 1000, "x": 0, "size": 10}}},
    "source.fwhm_fraction": {"source": {"shape": "gaussian", "fwhm_fraction": None}},
    "source.k0_dk": {"source": {"k0_dk": float("inf")}},
    "fig5.density": {"fig5": {"density": float("nan")}},
    "fig3.densities[0]": {"fig3": {"densities": [0.0001, 1.0]}},
    "fig5.n_alines too large": {"fig5": {"n_alines": 1000000}},
}
#: scan tables (tab-separated) that must be refused, and the key expected in the error.
BAD_TABLES = {
    "empty": "density\tk0_dk\tspectrum\n",
    "duplicate": "density\tk0_dk\tspectrum\n4.0\t10.0\trectangular\n4.0\t10.0\trectangular\n",
}


@pytest.fixture(scope="module")
def repo(tmp_path_factory, config_runs) -> Path:
    """A copy of the repository (dry runs write .snakemake metadata)."""
    return config_runs.copy_repo(tmp_path_factory.mktemp("cfg") / "repo")


@pytest.fixture(scope="module")
def merged(repo_root, config_runs) -> dict:
    """The CI configuration as Snakemake merges it (defaults, then ci.yaml)."""
    base = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())
    return config_runs.merge(
        base, yaml.safe_load((repo_root / "workflow/config/ci.yaml").read_text())
    )


@pytest.fixture(scope="module")
def schema(repo_root) -> dict:
    return yaml.safe_load((repo_root / SCHEMA).read_text())


@pytest.mark.slow
@pytest.mark.parametrize("key", list(BAD_CONFIGS))
def test_bad_config_stops_before_any_job(repo, key, config_runs):
    path = repo / f"bad_{abs(hash(key))}.yaml"
    path.write_text(yaml.safe_dump(BAD_CONFIGS[key]))
    config_runs.assert_refused(config_runs.dry_run(repo, path.name), key)
    assert not (repo / "results").exists()


@pytest.mark.slow
@pytest.mark.parametrize("name", list(BAD_TABLES))
def test_bad_scan_table_stops_before_any_job(repo, name, config_runs):
    table = repo / f"scan_{name}.tsv"
    table.write_text(BAD_TABLES[name])
    cfg = repo / f"scan_{name}.yaml"
    cfg.write_text(yaml.safe_dump({"scan": {"table": table.name}}))
    config_runs.assert_refused(config_runs.dry_run(repo, cfg.name), "scan.table")
    assert not (repo / "results").exists()


@pytest.mark.parametrize("key", [k for k in BAD_CONFIGS if k != "fig3.method"])
def test_check_config_names_the_key(merged, schema, key, config_runs):
    """The same cases directly (``fig3.method`` is the schema's enum, tested below)."""
    with pytest.raises(ValueError, match=key.split(" ")[0].replace("[", r"\[").replace("]", r"\]")):
        check_config(config_runs.merge(merged, BAD_CONFIGS[key]), schema)


def test_good_configs_pass(merged, schema, repo_root, config_runs):
    check_config(merged, schema)
    base = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())
    check_config(base, schema)
    # a Gaussian source with its width is fine; the step of 1 pixel in tracking too
    check_config(
        config_runs.merge(merged, {"source": {"shape": "gaussian", "fwhm_fraction": 0.5}}), schema
    )


def test_scan_table_checks():
    rows = [{"density": 4.0, "k0_dk": 10.0, "spectrum": "rectangular"}]
    check_scan_table(rows, 256)
    with pytest.raises(ValueError, match=r"scan.table.*no rows"):
        check_scan_table([], 256)
    with pytest.raises(ValueError, match=r"scan.table: rows 1 and 2"):
        check_scan_table(rows * 2, 256)
    with pytest.raises(ValueError, match="row 1 density"):
        check_scan_table([{**rows[0], "density": 1e-4}], 256)


def test_schema_method_enum_matches_the_package(schema):
    """The schema lists exactly the registered synthesis methods (kept in sync)."""
    enum = schema["properties"]["fig3"]["properties"]["method"]["enum"]
    assert sorted(enum) == sorted(speckle.ASCAN_METHODS)
    for sec in ("fig4", "fig6"):
        assert schema["properties"][sec]["properties"]["method"]["enum"] == enum
    assert schema["properties"]["speed_accuracy"]["properties"]["methods"]["items"]["enum"] == enum


OLD_FRAGMENT = {"fig2": {"fragment": {"depth": 10, "aline": 3, "size": 4}}}


def test_the_retired_fragment_key_is_read_as_x_with_a_warning(merged, schema, config_runs):
    """``fragment.aline`` (before issue 32) is ``fragment.x``: an old config still loads,
    warning; one giving both is refused, naming the key."""
    config = config_runs.merge(merged, OLD_FRAGMENT)  # merged over the defaults: both keys
    with pytest.warns(FutureWarning, match=r"fig2\.fragment\.aline is now fig2\.fragment\.x"):
        rename_retired_keys(config, given=[OLD_FRAGMENT])
    assert config["fig2"]["fragment"] == {"depth": 10, "x": 3, "size": 4}
    check_config(config, schema)
    both = {"fig2": {"fragment": {"depth": 10, "aline": 3, "x": 3, "size": 4}}}
    with pytest.raises(
        ValueError, match=r"fig2\.fragment has both 'aline'.*give only fig2\.fragment\.x"
    ):
        rename_retired_keys(config_runs.merge(merged, both), given=[both])
    # layered files (e.g. ci.yaml, then an old override): the last one naming either key wins
    new_x = {"fig2": {"fragment": {"x": 1}}}
    for given, x in (([new_x, OLD_FRAGMENT], 3), ([OLD_FRAGMENT, new_x], 1)):
        config = config_runs.merge(config_runs.merge(merged, given[0]), given[1])
        with pytest.warns(FutureWarning, match=r"fig2\.fragment\.aline is now"):
            rename_retired_keys(config, given=given)
        assert config["fig2"]["fragment"] == {"depth": 10, "x": x, "size": 4}
    with pytest.raises(ValueError, match=r"fig5\.fragment has both"):  # a config as a whole
        rename_retired_keys({"fig5": {"fragment": {"aline": 0, "x": 0}}})
    current = config_runs.merge(merged, {})
    rename_retired_keys(current, given=[{}])  # nothing retired: no warning (-W error below)
    assert current == merged


@pytest.mark.filterwarnings("error::FutureWarning")
def test_a_current_config_does_not_warn(merged):
    config = dict(merged)
    rename_retired_keys(config, given=[merged])


@pytest.mark.slow
def test_an_old_config_loads_with_a_warning_and_both_keys_stop(repo, config_runs):
    old = repo / "old_fragment.yaml"
    old.write_text(yaml.safe_dump(OLD_FRAGMENT))
    proc = config_runs.dry_run(repo, old.name)
    assert proc.returncode == 0, proc.stdout[-3000:]
    assert "fig2.fragment.aline is now fig2.fragment.x" in proc.stdout
    both = repo / "both_fragment.yaml"
    both.write_text(
        yaml.safe_dump({"fig2": {"fragment": {"depth": 10, "aline": 3, "x": 3, "size": 4}}})
    )
    config_runs.assert_refused(config_runs.dry_run(repo, both.name), "fig2.fragment")
