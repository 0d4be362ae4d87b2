"""The exported tables (`viewer.table_export`, `skyscatter export-tables`) read back by code that
did not write them: KTX2 by a parser of the KTX 2.0 specification written here, EXR by a decoder
of the OpenEXR file layout (header and ZIP blocks) written here, npz by numpy; the sidecar's
constants against the preset file and published numbers; the HLSL through glslang's HLSL
front end."""

from __future__ import annotations

import json
import math
import re
import shutil
import struct
import subprocess
import tomllib
import zlib
from pathlib import Path

import numpy as np
import pytest

import skyscatter
from exr_header import exr_header
from skyscatter import api
from skyscatter.spectrum.grid import wavelength_grid
from skyscatter.transport.table_store import cached_tables
from skyscatter.transport.tables import TableResolution
from skyscatter.viewer.shader_export import glsl_snippet, glsl_to_hlsl, hlsl_snippet
from skyscatter.viewer.table_export import ExportSettings, export_tables

KTX2_IDENTIFIER = bytes([0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A])
# IEC 61966-2-1 (sRGB) XYZ -> linear RGB, as the standard prints it (4 decimals)
SRGB_FROM_XYZ = np.array([[3.2406, -1.5372, -0.4986], [-0.9689, 1.8758, 0.0415],
                          [0.0557, -0.2040, 1.0570]])
# IAU 2015 nominal solar radius over the astronomical unit (IAU 2012 B2) [rad]
SUN_ANGULAR_RADIUS_RAD = 695_700.0 / 149_597_870.7


@pytest.fixture(scope="session")
def preview():
    """Earth's preview tables (the viewer's: 8 bins, half-size tables), and its profile."""
    atmosphere = api.load_atmosphere("earth")
    profile = atmosphere.optical_profile(wavelength_grid(8))
    tables = cached_tables(profile, TableResolution().scaled(0.5), atmosphere.scattering_orders)
    return atmosphere, profile, tables


def export(preview, folder: Path, **settings) -> dict:
    _, profile, tables = preview
    exported = export_tables(tables, profile, folder, ExportSettings(label="earth", **settings))
    return exported.sidecar


def read_ktx2(path: Path) -> dict:
    """The fields of a KTX 2.0 file (Khronos KTX File Format Specification 2.0, sections 3.1-3.9)
    and its one level's bytes, read from the specification's layout."""
    data = path.read_bytes()
    assert data[:12] == KTX2_IDENTIFIER
    header = dict(zip(("vk_format", "type_size", "width", "height", "depth", "layers", "faces",
                       "levels", "supercompression"), struct.unpack_from("<9I", data, 12),
                      strict=True))
    dfd_offset, dfd_length, kvd_offset, kvd_length = struct.unpack_from("<4I", data, 48)
    sgd_offset, sgd_length = struct.unpack_from("<2Q", data, 64)
    offset, length, uncompressed = struct.unpack_from("<3Q", data, 80)
    assert dfd_offset == 80 + 24 * header["levels"]
    total, = struct.unpack_from("<I", data, dfd_offset)
    assert total == dfd_length
    word0, version, block_size = struct.unpack_from("<IHH", data, dfd_offset + 4)
    model, primaries, transfer, flags = data[dfd_offset + 12:dfd_offset + 16]
    bytes_plane = data[dfd_offset + 20:dfd_offset + 28]
    samples = [struct.unpack_from("<HBB4BII", data, dfd_offset + 28 + 16 * k)
               for k in range((block_size - 24) // 16)]
    key_values, position = {}, kvd_offset
    while position < kvd_offset + kvd_length:
        size, = struct.unpack_from("<I", data, position)
        key, _, value = data[position + 4:position + 4 + size].partition(b"\0")
        key_values[key.decode()] = value.rstrip(b"\0").decode()
        position += 4 + size + (-size % 4)
    return dict(header, dfd=dict(word0=word0, version=version, block_size=block_size,
                                 model=model, primaries=primaries, transfer=transfer,
                                 flags=flags, bytes_plane=bytes_plane, samples=samples),
                sgd=(sgd_offset, sgd_length), level=(offset, length, uncompressed),
                key_values=key_values, level_data=data[offset:offset + length])


def read_exr(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    """(header attributes, channels by name) of a scanline OpenEXR file without or with ZIP
    compression, decoded from the file layout ("OpenEXR File Layout", openexr.com: header,
    offset table, chunks of 16 scanlines of zlib data de-interleaved and delta-decoded)."""
    data = path.read_bytes()
    attributes, position = exr_header(data)
    channels, raw = [], attributes["channels"][1]
    while raw[0] != 0:
        name, raw = raw.split(b"\0", 1)
        pixel_type, = struct.unpack_from("<i", raw, 0)
        channels.append((name.decode(), {1: np.dtype("<f2"), 2: np.dtype("<f4")}[pixel_type]))
        raw = raw[16:]
    x0, y0, x1, y1 = struct.unpack("<4i", attributes["dataWindow"][1])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    compression = attributes["compression"][1][0]
    lines_per_chunk = {0: 1, 3: 16}[compression]  # NO_COMPRESSION, ZIP_COMPRESSION
    chunks = -(-height // lines_per_chunk)
    offsets = struct.unpack_from(f"<{chunks}Q", data, position)
    planes = {name: np.empty((height, width), dtype) for name, dtype in channels}
    for offset in offsets:
        y, size = struct.unpack_from("<ii", data, offset)
        block = data[offset + 8:offset + 8 + size]
        lines = min(lines_per_chunk, y1 + 1 - y)
        expected = lines * width * sum(dtype.itemsize for _, dtype in channels)
        if size < expected:
            packed = np.frombuffer(zlib.decompress(block), np.uint8).astype(np.int32)
            packed = (np.cumsum(packed - 128) + 128) % 256  # undo the predictor ...
            half = (packed.size + 1) // 2  # ... and the interleaving
            block = np.empty(packed.size, np.uint8)
            block[0::2], block[1::2] = packed[:half], packed[half:]
            block = block.tobytes()
        start = 0
        for row in range(lines):
            for name, dtype in channels:
                count = width * dtype.itemsize
                planes[name][y - y0 + row] = np.frombuffer(block[start:start + count], dtype)
                start += count
    return attributes, planes


def test_npz_holds_the_tables_in_texture_order_with_names(preview, tmp_path):
    _, profile, tables = preview
    sidecar = export(preview, tmp_path / "npz", format="npz", colour="spectral",
                     precision="float")
    with np.load(tmp_path / "npz" / "tables.npz") as archive:
        arrays = dict(archive)
    assert set(arrays) == {"transmittance", "irradiance", "scattering", "phase",
                           "wavelengths_nm"}
    np.testing.assert_array_equal(arrays["wavelengths_nm"], profile.wavelengths_nm)
    # spectral channels are the tables themselves (float32 rounding only)
    np.testing.assert_allclose(arrays["transmittance"], tables.transmittance, rtol=1e-6)
    np.testing.assert_allclose(arrays["irradiance"], tables.irradiance, rtol=1e-6)
    n_r, n_mu, n_mu_s, n_nu, n_t, n_wl = tables.scattering.shape
    s = sidecar["scattering_shape"]
    assert (s["n_r"], s["n_mu"], s["n_mu_s"], s["n_nu"], s["n_tables"]) == (
        n_r, n_mu, n_mu_s, n_nu, n_t)
    packed = arrays["scattering"]
    assert packed.shape == (n_t * n_r, n_mu, n_nu * n_mu_s, n_wl)
    # Bruneton 2017's packing: texel (x, y, z) = (nu * n_mu_s + mu_s, mu, table * n_r + r)
    rng = np.random.default_rng(3)
    for _ in range(20):
        r, mu, mu_s, nu, t = (rng.integers(n) for n in (n_r, n_mu, n_mu_s, n_nu, n_t))
        np.testing.assert_allclose(packed[t * n_r + r, mu, nu * n_mu_s + mu_s],
                                   tables.scattering[r, mu, mu_s, nu, t], rtol=1e-6)
    phase = arrays["phase"]
    for s_index in range(n_t - 1):
        angle = 2049
        row = s_index * sidecar["uniforms"]["u_phase_rows"] + angle // 1024
        np.testing.assert_allclose(phase[row, angle % 1024],
                                   tables.lookup_phase[s_index, angle], rtol=1e-6)


def test_sidecar_states_the_atmosphere_and_its_parameterisation(preview, tmp_path):
    atmosphere, profile, tables = preview
    sidecar = export(preview, tmp_path / "x", format="npz", colour="rgb")
    with open(Path(skyscatter.__file__).parent / "atmosphere" / "presets" / "earth.toml",
              "rb") as file:
        preset = tomllib.load(file)
    assert sidecar["bottom_radius_m"] == preset["planet"]["radius_m"]
    assert sidecar["top_radius_m"] == (preset["planet"]["radius_m"]
                                       + preset["atmosphere"]["top_altitude_m"])
    # mu_s_min: the tables reach the sun 30 deg below the horizon (transport/tables.py)
    assert sidecar["mu_s_min"] == pytest.approx(math.cos(math.radians(120.0)), abs=1e-12)
    # the sun at distance_au = 1: IAU nominal radius / au, to the 4 digits of 1 AU's variation
    assert sidecar["sun_angular_radius_rad"] == pytest.approx(SUN_ANGULAR_RADIUS_RAD, rel=1e-3)
    assert sidecar["orders"] == preset["tables"]["orders"]
    assert sidecar["chromaticities"] == pytest.approx([0.64, 0.33, 0.30, 0.60, 0.15, 0.06,
                                                       0.3127, 0.3290])
    assert sidecar["channels"] == ["R", "G", "B"] and sidecar["colour_space"] == "srgb"
    assert sidecar["atmosphere"] == "earth" and len(sidecar["atmosphere_fingerprint"]) == 64
    assert sidecar["skyscatter_version"] == skyscatter.__version__
    uniforms = sidecar["uniforms"]
    assert uniforms["u_bottom_radius"] == sidecar["bottom_radius_m"]
    assert uniforms["u_radius_warp"][:tables.radius_warp.size] == tables.radius_warp.tolist()
    # every uniform the GLSL declares is in the sidecar, and nothing else
    declared = set(re.findall(r"^uniform\s+(?:highp\s+)?\w+\s+(\w+)", glsl_snippet(),
                              flags=re.MULTILINE))
    samplers = {"u_transmittance", "u_irradiance", "u_scattering", "u_phase"}
    assert set(uniforms) == declared - samplers
    assert json.loads((tmp_path / "x" / "tables.json").read_text()) == sidecar


@pytest.mark.parametrize("precision", ["half", "float"])
def test_ktx2_files_follow_the_specification(preview, tmp_path, precision):
    sidecar = export(preview, tmp_path / "k", format="ktx2", colour="xyz", precision=precision)
    npz = export(preview, tmp_path / "n", format="npz", colour="xyz", precision=precision)
    assert npz["scales"] == sidecar["scales"]
    with np.load(tmp_path / "n" / "tables.npz") as archive:
        arrays = dict(archive)
    size = {"half": 2, "float": 4}[precision]
    for name, entry in sidecar["tables"].items():
        ktx = read_ktx2(tmp_path / "k" / entry["files"][0])
        # Vulkan: VK_FORMAT_R16G16B16A16_SFLOAT = 97, VK_FORMAT_R32G32B32A32_SFLOAT = 109
        assert ktx["vk_format"] == {2: 97, 4: 109}[size] and ktx["type_size"] == size
        assert (ktx["width"], ktx["height"], ktx["depth"]) == (
            entry["width"], entry["height"], entry["depth"])
        assert (ktx["layers"], ktx["faces"], ktx["levels"], ktx["supercompression"]) == (
            0, 1, 1, 0)
        assert ktx["sgd"] == (0, 0)
        dfd = ktx["dfd"]
        # basic descriptor block, version 1.3 (2), 4 samples; RGBSDA, CIE XYZ primaries (5),
        # linear transfer; one plane of 4 channels
        assert (dfd["word0"], dfd["version"], dfd["block_size"]) == (0, 2, 24 + 4 * 16)
        assert (dfd["model"], dfd["primaries"], dfd["transfer"]) == (1, 5, 1)
        assert dfd["bytes_plane"] == bytes([4 * size, 0, 0, 0, 0, 0, 0, 0])
        for k, (offset, bits, channel, *position, lower, upper) in enumerate(dfd["samples"]):
            assert (offset, bits + 1) == (8 * size * k, 8 * size)
            assert channel == 0x80 | 0x40 | (0, 1, 2, 15)[k]  # FLOAT | SIGNED | R, G, B, A
            assert position == [0, 0, 0, 0]
            assert struct.unpack("<2f", struct.pack("<2I", lower, upper)) == (-1.0, 1.0)
        offset, length, uncompressed = ktx["level"]
        texels = entry["width"] * entry["height"] * max(entry["depth"], 1)
        assert length == uncompressed == texels * 4 * size
        assert offset % math.lcm(4 * size, 4) == 0
        assert ktx["key_values"]["KTXwriter"].startswith("skyscatter")
        values = np.frombuffer(ktx["level_data"], {2: "<f2", 4: "<f4"}[size])
        values = values.reshape(arrays[name].shape[:-1] + (4,))
        np.testing.assert_array_equal(values[..., :3], arrays[name])
        assert not values[..., 3].any()


def test_spectral_ktx2_splits_wavelengths_into_groups_of_four(preview, tmp_path):
    sidecar = export(preview, tmp_path / "k", format="ktx2", colour="spectral")
    assert sidecar["tables"]["transmittance"]["files"] == ["transmittance_0.ktx2",
                                                           "transmittance_1.ktx2"]
    ktx = read_ktx2(tmp_path / "k" / "transmittance_1.ktx2")
    assert ktx["dfd"]["primaries"] == 0  # unspecified: the channels are wavelengths
    values = np.frombuffer(ktx["level_data"], "<f2").reshape(ktx["height"], ktx["width"], 4)
    _, _, tables = preview
    scale = sidecar["scales"]["transmittance"]
    # wavelengths 4-7; float16 keeps 11 significant bits (relative 2^-11)
    np.testing.assert_allclose(values * scale, tables.transmittance[..., 4:8], rtol=2**-11,
                               atol=scale)


@pytest.mark.parametrize("colour", ["rgb", "spectral"])
def test_exr_files_read_back_with_a_decoder_of_the_file_layout(preview, tmp_path, colour):
    sidecar = export(preview, tmp_path / "e", format="exr", colour=colour)
    export(preview, tmp_path / "n", format="npz", colour=colour)
    with np.load(tmp_path / "n" / "tables.npz") as archive:
        arrays = dict(archive)
    names = sidecar["channels"]
    if colour == "spectral":  # Fichet et al. 2021: layer S0, wavelength with a decimal comma
        assert [float(n[3:-2].replace(",", ".")) for n in names] == sidecar["wavelengths_nm"]
    for name, entry in sidecar["tables"].items():
        attributes, planes = read_exr(tmp_path / "e" / entry["files"][0])
        assert set(planes) == set(names) and planes[names[0]].dtype == np.float16
        atlas = np.stack([planes[c] for c in names], axis=-1)
        # the 3-D table: its z slices stacked downwards, row z * height + y
        np.testing.assert_array_equal(atlas, arrays[name].reshape(atlas.shape))
        assert json.loads(attributes["skyscatter_scale"][1]) == sidecar["scales"][name]
        if colour == "rgb":
            chromaticities = struct.unpack("<8f", attributes["chromaticities"][1])
            assert chromaticities == pytest.approx(sidecar["chromaticities"], abs=1e-6)
        else:
            assert "chromaticities" not in attributes


def test_rgb_tables_are_the_xyz_tables_in_srgb(preview, tmp_path):
    rgb = export(preview, tmp_path / "rgb", format="npz", colour="rgb", precision="float")
    xyz = export(preview, tmp_path / "xyz", format="npz", colour="xyz", precision="float")
    with np.load(tmp_path / "rgb" / "tables.npz") as a, np.load(tmp_path / "xyz" / "tables.npz") \
            as b:
        # the linear tables: the sRGB standard's matrix (4 decimals: 3e-4 of the largest
        # coefficient, times the XYZ magnitudes)
        for name in ("irradiance", "scattering"):
            expected = b[name] @ SRGB_FROM_XYZ.T
            np.testing.assert_allclose(a[name], expected, rtol=0,
                                       atol=3e-4 * 6 * np.abs(b[name]).max())
        assert a["transmittance"].min() >= 0.0 and a["transmittance"].max() <= 1.0
    # the sun's colour: its XYZ in sRGB
    np.testing.assert_allclose(rgb["sun_irradiance"], SRGB_FROM_XYZ @ xyz["sun_irradiance"],
                               rtol=1e-3)


def test_hlsl_is_the_glsl_translated_and_compiles(tmp_path):
    hlsl = hlsl_snippet()
    code = "\n".join(line.split("//")[0] for line in hlsl.splitlines())
    for glsl_only in ("vec2", "vec3", "vec4", "mix(", "texture(", "texelFetch(", "greaterThan(",
                      "sampler2D", "sampler3D", "highp"):
        assert glsl_only not in code
    assert glsl_to_hlsl("vec3 a = mix(vec3(0.0), b, greaterThan(c, vec3(1.0)));") == \
        "float3 a = lerp(((float3)(0.0)), b, (c > ((float3)(1.0))));"
    assert glsl_to_hlsl("float t = atan(y, x); // mix(a, b) stays in comments") == \
        "float t = atan2(y, x); // mix(a, b) stays in comments"
    with pytest.raises(ValueError, match="no rule for the GLSL call fract"):
        glsl_to_hlsl("float f = fract(x);")
    validator = shutil.which("glslangValidator")
    if validator is None:
        pytest.skip("glslangValidator (apt-get install glslang-tools) compiles the HLSL")
    main = ("\nfloat4 main(float4 position : SV_Position) : SV_Target {\n"
            "    float3 origin = float3(0.0, 0.0, u_bottom_radius + 2.0);\n"
            "    float3 dir = normalize(float3(position.xy / 64.0 - 0.5, 1.0));\n"
            "    float3 inscattered;\n"
            "    float3 t = aerial_perspective(origin, origin + 1e3 * dir, dir, inscattered);\n"
            "    return float4(sky_radiance(origin, dir, float3(0.0, 0.0, 1.0), 1.0)\n"
            "                  + t * inscattered + sun_transmittance(origin, dir), 1.0);\n}\n")
    source = tmp_path / "probe.hlsl"
    source.write_text(hlsl + main)
    result = subprocess.run([validator, "-D", "-S", "frag", "-e", "main", "-V", "-o",
                             str(tmp_path / "probe.spv"), str(source)], capture_output=True,
                            text=True)
    assert result.returncode == 0, result.stdout + result.stderr


def test_the_glsl_example_of_the_docs_compiles(tmp_path):
    validator = shutil.which("glslangValidator")
    if validator is None:
        pytest.skip("glslangValidator (apt-get install glslang-tools) compiles the example")
    docs = (Path(__file__).parents[2] / "docs" / "engines.md").read_text()
    example = re.search(r"```glsl\n(.*?)```", docs, flags=re.DOTALL)[1]
    marker = "// ... skyscatter_tables.glsl pasted or included here ...\n"
    assert marker in example
    source = tmp_path / "example.frag"
    source.write_text(example.replace(marker, glsl_snippet()))
    result = subprocess.run([validator, str(source)], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
