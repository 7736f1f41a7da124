"""Report captions render as reStructuredText: no docutils messages, parameters for people.

Captions are Jinja templates filled with ``snakemake.config`` (as ``snakemake --report`` does),
then parsed by docutils. A bare ``|x|`` is a reStructuredText substitution reference (math goes
in ``:math:``), and a config mapping must not be printed as a Python dict. The report built by
Snakemake itself is checked in ``tests/pipeline/test_pipeline.py``.
"""

from __future__ import annotations

import io
from types import SimpleNamespace

import docutils.core
import jinja2
import pytest
import yaml

CONFIGS = ("workflow/config/config.yaml", "workflow/config/ci.yaml")


def merged(repo_root, name: str) -> dict:
    """The default config with ``name`` layered over it (nested keys replace what they name)."""

    def merge(base: dict, over: dict) -> dict:
        for k, v in over.items():
            base[k] = (
                merge(base[k], v) if isinstance(v, dict) and isinstance(base.get(k), dict) else v
            )
        return base

    default = yaml.safe_load((repo_root / CONFIGS[0]).read_text())
    return merge(default, yaml.safe_load((repo_root / name).read_text()))


def captions(repo_root) -> list:
    return sorted((repo_root / "workflow" / "report").glob("*.rst"))


@pytest.mark.parametrize("config", CONFIGS)
def test_captions_render_without_docutils_messages(repo_root, config):
    cfg = merged(repo_root, config)
    assert captions(repo_root)
    for path in captions(repo_root):
        text = jinja2.Template(path.read_text()).render(snakemake=SimpleNamespace(config=cfg))
        messages = io.StringIO()
        docutils.core.publish_string(
            text,
            writer="html",
            settings_overrides={"warning_stream": messages, "report_level": 1, "halt_level": 5},
        )
        assert messages.getvalue() == "", f"{path.name}:\n{messages.getvalue()}"
        assert "{'" not in text and "[{" not in text, f"{path.name} prints a dict:\n{text}"


def test_strain_ranges_are_written_for_people(repo_root):
    cfg = merged(repo_root, CONFIGS[0])
    path = repo_root / "workflow" / "report" / "fig6b.rst"
    text = jinja2.Template(path.read_text()).render(snakemake=SimpleNamespace(config=cfg))
    s = cfg["fig6"]["panel_b"]["strain"]
    assert f"{100 * s['start']:g} to {100 * s['stop']:g} % in {s['num']} points" in text
