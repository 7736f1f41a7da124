"""The SynthOCT files: INI, phantoms, PNG scans and the baseline's phantoms (issue 33)."""

from __future__ import annotations

import dataclasses
import hashlib
from importlib.resources import files

import numpy as np
import pytest

import speckle
from speckle.synthoct.files import (
    INI_KEYS,
    ScannerConfig,
    baseline_table,
    read_phantom_table,
    read_png,
)

DATA = files("speckle.data") / "synthoct"

#: git blob hashes of the published phantom files (SynthOCT_Baseline, self-consistency_check/;
#: the files themselves are too large to ship): written on Windows, CRLF line ends.
BLOBS = {
    ("uniform", 42): "48caa53c59a0037f5872313c514fe702514fe1c2",
    ("uniform", 101): "2b989bb64cade0c8a0b743505907f147a63b3199",
    ("layers", 42): "164448139fa1e423cd7d6497b908ec66ce5b8524",
    ("layers", 101): "4365e80280c7440d1acf1d66853463cb2ce17029",
}

OFFICIAL_INI = """[Parameters]
scan filename = Scan_Raw.bin
scatterers coordinates file = Scatterers_Exp.txt
a-scan pixel numbers = 256
vertical pixel size mcm = 6.0
central wavelength mcm = 1.3
number of a-scans in b-scan = 512
xmax mcm = 3072.0
number of b-scans = 1
ymax mcm = 0.0
beam radius mcm = 10.0
number of scatterers in b-scan = 300000
"""


def _blob_sha1(data: bytes) -> str:
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


# --- configuration ------------------------------------------------------------------------


def test_official_ini_reads_as_the_challenge_defaults(tmp_path):
    p = tmp_path / "Configuration.ini"
    p.write_text(OFFICIAL_INI)
    assert speckle.read_scanner_config(p) == ScannerConfig()
    # the baseline's own writer (configparser) keeps the keys' case from Part1_Generator.py
    p.write_text(OFFICIAL_INI.replace("xmax mcm", "Xmax mcm").replace("beam radius", "Beam Radius"))
    assert speckle.read_scanner_config(p) == ScannerConfig()


def test_config_round_trip(tmp_path):
    cfg = ScannerConfig(n_pixels=601, pixel_size=2.2, n_lines=975, x_max=3000.0,
                        beam_radius=6.0, n_scatterers=255_000, y_max=12.5, n_bscans=3)  # fmt: skip
    speckle.write_scanner_config(cfg, tmp_path / "c.ini")
    assert speckle.read_scanner_config(tmp_path / "c.ini") == cfg
    assert cfg.depth_range == pytest.approx(601 * 2.2)
    np.testing.assert_allclose(cfg.bscan_positions, [-6.25, -6.25 + 12.5 / 3, -6.25 + 25 / 3])


def test_geometry_of_the_challenge():
    cfg = ScannerConfig()
    np.testing.assert_array_equal(cfg.line_positions, -1536.0 + 6.0 * np.arange(512))
    np.testing.assert_array_equal(cfg.bscan_positions, [0.0])
    assert cfg.k0 == pytest.approx(2 * np.pi / 1.3)


@pytest.mark.parametrize("key", list(INI_KEYS))
def test_missing_key_is_named(tmp_path, key):
    text = "\n".join(line for line in OFFICIAL_INI.splitlines() if not line.startswith(key))
    p = tmp_path / "c.ini"
    p.write_text(text)
    with pytest.raises(ValueError, match=f"missing key '{key}'"):
        speckle.read_scanner_config(p)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda s: s + "transparencycoeff = 1\n", "unknown key 'transparencycoeff'"),
        (lambda s: s.replace("= 256", "= 256.5"), "'a-scan pixel numbers' must be an integer"),
        (lambda s: s.replace("= 1.3", "= abc"), "'central wavelength mcm' must be a number"),
        (lambda s: s.replace("= 10.0", "= -1"), "beam_radius .'beam radius mcm'. must be > 0"),
        (lambda s: s.replace("= 10.0", "= nan"), "beam_radius .'beam radius mcm'. must be finite"),
        (lambda s: s.replace("[Parameters]", "[Params]"), r"missing section \[Parameters\]"),
        (lambda s: s + "[Other]\na = 1\n", "unknown section"),
        (lambda s: s.replace("= 300000", "= 0"), r"n_scatterers .* must be >= 1"),
    ],
)
def test_bad_ini_is_refused_naming_the_key(tmp_path, edit, match):
    p = tmp_path / "c.ini"
    p.write_text(edit(OFFICIAL_INI))
    with pytest.raises(ValueError, match=match) as err:
        speckle.read_scanner_config(p)
    assert str(p) in str(err.value)


def test_config_is_frozen_and_typed():
    cfg = ScannerConfig()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.n_pixels = 3
    with pytest.raises(TypeError, match="n_lines"):
        ScannerConfig(n_lines=5.0)
    with pytest.raises(ValueError, match="y_max"):
        ScannerConfig(y_max=-1.0)


# --- phantoms -----------------------------------------------------------------------------


@pytest.mark.parametrize(("kind", "seed"), list(BLOBS))
def test_baseline_phantoms_are_the_published_files_byte_for_byte(tmp_path, kind, seed):
    """Regenerated, written by write_phantom and given Windows line ends, each phantom has the
    git blob hash of the published file: the same 300,000 x 4 numbers, digit for digit."""
    path = tmp_path / "s.txt"
    speckle.write_phantom(baseline_table(kind, seed), path)
    data = path.read_bytes().replace(b"\n", b"\r\n")
    assert _blob_sha1(data) == BLOBS[kind, seed]
    # the scene form writes the same file (energy through sqrt(E/100) and back)
    speckle.write_phantom(speckle.baseline_phantom(kind, seed), path)
    assert _blob_sha1(path.read_bytes().replace(b"\n", b"\r\n")) == BLOBS[kind, seed]


def test_baseline_recipe():
    t = baseline_table("layers", 42)
    assert t.shape == (300_000, 4)
    assert set(np.unique(t[t[:, 2] > 400.5, 3])) == {2.5}
    assert set(np.unique(t[t[:, 2] < 399.5, 3])) == {0.01}
    assert np.all(np.abs(t[:, 1]) <= 10.0) and np.all(np.abs(t[:, 0]) <= 1536.0)
    u = baseline_table("uniform", 42)
    np.testing.assert_array_equal(u[:, :3], t[:, :3])  # same draws, only the energies differ
    assert np.all(u[:, 3] == 1.0)
    a = speckle.baseline_phantom("uniform", "A")
    np.testing.assert_array_equal(a.z.values, u[:, 2])
    with pytest.raises(ValueError, match="kind"):
        baseline_table("layered", 42)
    with pytest.raises(ValueError, match="seed"):
        speckle.baseline_phantom("uniform", "C")


def test_phantom_round_trip_and_dat(tmp_path):
    t = np.array([[-1.5, 0.25, 10.0, 1.0], [3.0, -2.0, 1535.0, 100.0], [0.0, 0.0, 0.0, 0.0]])
    for name in ("p.txt", "p.dat"):
        speckle.write_phantom(t, tmp_path / name)
        np.testing.assert_array_equal(read_phantom_table(tmp_path / name), t)
    ph = speckle.read_phantom(tmp_path / "p.dat")
    np.testing.assert_allclose(ph.amplitude.values, [0.1, 1.0, 0.0])
    assert ph.amplitude.dtype == np.complex128 and speckle.scene.shared.is_shared(ph)


def _write(tmp_path, text: str):
    p = tmp_path / "s.txt"
    p.write_text(text)
    return p


GOOD = "0 0 10 1\n1 0 20 1\n"


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (GOOD + "1 2 3\n", "line 3: 3 columns, expected 4"),
        (GOOD + "1 2 3 4 5\n", "line 3: 5 columns"),
        ("0 0 10 1\n\n1 2 x 4\n", "line 3: 'x' is not a number"),
        ("0,0,10,1\n", "line 1: 1 columns"),
        (GOOD + "1 2 nan 4\n", "line 3: NaN or infinite"),
        (GOOD + "1 2 3 inf\n", "line 3: NaN or infinite"),
        (GOOD + "1 2 3 100.5\n", "line 3: energy 100.5 % outside 0..100"),
        ("0 0 10 -1e-3\n" + GOOD, "line 1: energy -0.001 % outside 0..100"),
        ("X Y Z Energy\n" + GOOD, "line 1: 'X' is not a number"),
        ("\n \n", "no scatterers"),
    ],
)
def test_bad_phantom_is_refused_naming_the_line(tmp_path, text, match):
    p = _write(tmp_path, text)
    with pytest.raises(ValueError, match=match) as err:
        speckle.read_phantom(p)
    assert str(p) in str(err.value)


def test_count_must_match_the_config(tmp_path):
    p = _write(tmp_path, GOOD)
    with pytest.raises(
        ValueError, match=r"2 scatterers, but .*'number of scatterers in b-scan' is 3"
    ):
        speckle.read_phantom(p, config=ScannerConfig(n_scatterers=3))
    assert speckle.read_phantom(p, config=ScannerConfig(n_scatterers=2)).sizes["scatterer"] == 2


def test_scatterers_outside_the_box_are_kept_and_counted(tmp_path):
    """The reader keeps every scatterer (the scanner images each by the same formula); the
    number outside |X| <= x_max/2, 0 <= Z <= H is recorded. The box is closed: %.4e rounding
    puts drawn scatterers on its far edges (1535.97 -> 1.5360e+03)."""
    text = "1536 0 1536 1\n1600 0 10 1\n0 50 -5 1\n0 0 1600 1\n0 0 10 1\n"
    ph = speckle.read_phantom(_write(tmp_path, text), config=ScannerConfig(n_scatterers=5))
    assert ph.sizes["scatterer"] == 5
    assert ph.attrs["n_outside_box"] == 3  # x = 1600, z = -5, z = 1600 (y is not bounded)
    np.testing.assert_array_equal(ph.z.values, [1536, 10, -5, 1600, 10])


def test_write_phantom_of_a_project_scene(tmp_path):
    """A scene built by the project is written as a phantom the scanner accepts: the count of
    the INI written beside it, energies in 0..100 (E = energy_scale |a|^2), Y = 0 in 2-D."""
    from speckle.scene.regions import background, layer

    regions = speckle.make_regions(background(density=2e-3), layer(300.0, 700.0, density=6e-3))
    scene = speckle.shared_scene(regions, z_range=(0, 1536), x_range=(-1536, 1536), seed=3)
    m = scene.sizes["scatterer"]
    cfg = dataclasses.replace(ScannerConfig(), n_scatterers=m)
    with pytest.raises(ValueError, match=r"outside 0\.\.100"):
        speckle.write_phantom(scene.assign(amplitude=scene.amplitude * 1.1), tmp_path / "p.txt")
    speckle.write_phantom(scene, tmp_path / "p.txt", config=cfg, energy_scale=1.0)
    speckle.write_scanner_config(cfg, tmp_path / "c.ini")
    back = speckle.read_phantom(tmp_path / "p.txt", config=speckle.read_scanner_config(
        tmp_path / "c.ini"))  # fmt: skip
    np.testing.assert_allclose(back.x.values, scene.x.values, rtol=1e-4, atol=1e-3)
    np.testing.assert_array_equal(back.y.values, 0.0)
    np.testing.assert_allclose(back.amplitude.real**2 * 100, np.abs(scene.amplitude) ** 2,
                               rtol=2e-4)  # fmt: skip
    with pytest.raises(ValueError, match="config's 'number of scatterers in b-scan'"):
        speckle.write_phantom(scene, tmp_path / "q.txt", config=ScannerConfig(), energy_scale=1.0)
    with pytest.raises(TypeError, match="shared scene"):
        speckle.write_phantom({"x": 1}, tmp_path / "q.txt")


# --- scans ----------------------------------------------------------------------------------


def test_published_scans_read_as_gray(tmp_path):
    scan = speckle.read_scan(DATA / "Scan_Exp1_Uniform_A.png")
    assert scan.dtype == np.uint8 and scan.dims == ("depth", "x") and scan.shape == (256, 512)
    np.testing.assert_array_equal(scan.x.values, ScannerConfig().line_positions)
    np.testing.assert_array_equal(scan.depth.values, 6.0 * np.arange(256))
    speckle.write_scan(scan, tmp_path / "s.png")
    back = speckle.read_scan(tmp_path / "s.png")
    np.testing.assert_array_equal(back.values, scan.values)
    from PIL import Image

    with Image.open(tmp_path / "s.png") as im:
        assert im.mode == "L"


def test_scan_refusals(tmp_path):
    with pytest.raises(TypeError, match="uint8"):
        speckle.write_scan(np.zeros((3, 3)), tmp_path / "s.png")
    with pytest.raises(ValueError, match="2-D"):
        speckle.write_scan(np.zeros((3, 3, 3), np.uint8), tmp_path / "s.png")
    with pytest.raises(ValueError, match="config expects"):
        speckle.read_scan(DATA / "Scan_Exp1_Uniform_A.png", config=ScannerConfig(n_lines=10))
    from PIL import Image

    rgb = np.zeros((4, 4, 3), np.uint8)
    rgb[0, 0] = (1, 2, 3)
    Image.fromarray(rgb).save(tmp_path / "c.png")
    with pytest.raises(ValueError, match="equal"):
        read_png(tmp_path / "c.png")
    assert not list(tmp_path.glob(".*tmp"))  # refused writes leave no temporary file
