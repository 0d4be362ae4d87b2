"""The GGX-prefiltered mip chain of a cube map (render.prefilter) against a literal numpy
version of Karis's (2013) first sum, the cosine-weighted irradiance it must become at
roughness 1, and the energy a normalised filter keeps; the files read back with OpenEXR."""

from __future__ import annotations

import numpy as np
import OpenEXR
import pytest

from skyscatter import api
from skyscatter.cli import main
from skyscatter.render.prefilter import prefiltered_mips

FACE, LEVELS = 32, 4


@pytest.fixture(scope="module")
def sky():
    camera = api.CubeMapCamera(FACE)
    image = api.render(api.load_atmosphere("earth"), camera, 60.0, 135.0,
                       wavelengths_nm=(450.0, 550.0, 650.0), solver="single")
    rgb = np.where(image.valid[..., None], image.rgb("srgb"), 0.0)
    return camera, rgb, prefiltered_mips(rgb, camera, LEVELS)


def _ggx_literal(n: np.ndarray, camera, rgb: np.ndarray, alpha: float) -> np.ndarray:
    """Karis (2013), eqs. 4-5 with n = v: sum L D(h) (n.l) dOmega / sum D(h) (n.l) dOmega,
    h = normalize(n + l), D = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2) (Walter et al.
    2007, eq. 33), over the texels of the map."""
    l, valid = camera.directions()
    omega = camera.pixel_solid_angles()
    h = l + n
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    d = alpha**2 / (np.pi * ((h @ n) ** 2 * (alpha**2 - 1.0) + 1.0) ** 2)
    w = np.where(valid, d * np.maximum(l @ n, 0.0) * omega, 0.0)
    return np.einsum("hw,hwc->c", w, rgb) / w.sum()


def test_level_0_is_the_map_and_the_faces_halve(sky):
    camera, rgb, chain = sky
    assert len(chain) == LEVELS
    np.testing.assert_array_equal(chain[0], rgb)
    for k, level in enumerate(chain):
        assert level.shape == (3 * (FACE >> k), 4 * (FACE >> k), 3)
        assert np.isfinite(level).all() and (level >= 0.0).all()


def test_a_level_is_the_literal_ggx_sum(sky):
    # Reference: the numpy sum above, over the full map (level k filters the full map while
    # its sum stays within PAIR_BUDGET: always at face 32), roughness k / 3, alpha its square;
    # the same sum in another order: 1e-10.
    camera, rgb, chain = sky
    rng = np.random.default_rng(4)
    for k in (1, 2):
        target = api.CubeMapCamera(FACE >> k)
        normals, valid = target.directions()
        rows, columns = np.nonzero(valid)
        for index in rng.choice(len(rows), 6, replace=False):
            i, j = rows[index], columns[index]
            expected = _ggx_literal(normals[i, j], camera, rgb, (k / 3) ** 2)
            np.testing.assert_allclose(chain[k][i, j], expected, rtol=1e-10)


def test_roughness_1_is_the_irradiance_over_pi(sky):
    # Reference: at alpha = 1 GGX is 1 / pi in every direction, so the top level is
    # E(n) / pi = sum L max(n.l, 0) dOmega / pi; the filter divides by its own sum of
    # max(n.l, 0) dOmega, pi to 3e-4 on texels of 32 a face (measured 3.2e-4 in every
    # channel); tolerance 1e-3.
    camera, rgb, chain = sky
    l, _ = camera.directions()
    omega = camera.pixel_solid_angles()
    top = api.CubeMapCamera(FACE >> (LEVELS - 1))
    normals, valid = top.directions()
    for i, j in zip(*np.nonzero(valid), strict=True):
        irradiance = np.einsum("hw,hwc->c", np.maximum(l @ normals[i, j], 0.0) * omega, rgb)
        np.testing.assert_allclose(chain[-1][i, j], irradiance / np.pi, rtol=1e-3)


def test_each_level_keeps_the_maps_energy(sky):
    # Identity: a filter that depends on n.l only and is normalised keeps int L dOmega over
    # the sphere; the sums over texels keep it to what the coarser texels' quadrature does:
    # measured 0.30 %, 0.11 %, 0.22 % at levels 1-3 with the sun's disk in the map; 1 %.
    camera, rgb, chain = sky
    total = np.einsum("hw,hwc->c", camera.pixel_solid_angles(), rgb)
    for k, level in enumerate(chain[1:], start=1):
        omega = api.CubeMapCamera(FACE >> k).pixel_solid_angles()
        np.testing.assert_allclose(np.einsum("hw,hwc->c", omega, level), total, rtol=0.01)


def test_the_command_line_writes_the_levels_beside_the_exr(tmp_path, capsys):
    common = ["render", "earth", "--camera", "cubemap", "--size", "8", "--solver", "single",
              "--wavelengths", "3", "-o", str(tmp_path / "sky.png")]
    assert main([*common, "--exr", str(tmp_path / "sky.exr"), "--mips", "3"]) == 0
    for k in (1, 2):
        exr = OpenEXR.File(str(tmp_path / f"sky_mip{k}.exr"), separate_channels=True)
        assert exr.channels()["G"].pixels.shape == (3 * (8 >> k), 4 * (8 >> k))
        assert exr.header()["chromaticities"] is not None
    assert not (tmp_path / "sky_mip3.exr").exists()
    capsys.readouterr()
    for extra, message in [(["--mips", "3"], "add --exr"),
                           (["--exr", str(tmp_path / "b.exr"), "--mips", "5"],
                            "--size must be a multiple of 16"),
                           (["--exr", str(tmp_path / "c.exr"), "--mips", "1"], "mips")]:
        assert main([*common, *extra]) == 2
        assert message in capsys.readouterr().err
    assert main(["render", "earth", "--size", "8", "--exr", str(tmp_path / "d.exr"),
                 "--mips", "2", "-o", str(tmp_path / "d.png")]) == 2
    assert "add --camera cubemap" in capsys.readouterr().err
    assert not (tmp_path / "b_mip1.exr").exists() and not (tmp_path / "d.png").exists()
