"""Benchmark: the viewer's GPU frame time on a real GPU (issue 18's "Measured").

The viewer's own GLSL ES 3.00 shaders (static/shaders, static/generated, composed as
viewer.js's PROGRAMS with its PREFIX) draw the viewer's frame off-screen in a native OpenGL
context (moderngl on EGL) from the same tables the server sends (`TableService.tables`, the
message of `gpu_tables.encode`, uploaded as tables.js does: RGB16F textures). Per frame, as
`Viewer.draw` with float render targets: the sky pass (main.frag, output "exposed") into an
RGBA16F target, then the composite pass (composite.frag) into an RGBA8 target of the same size
(the canvas); no stars (a clear sky without a date). Timed per frame with a GL_TIME_ELAPSED
query (GPU time) and as wall time from the first GL call to glFinish; the median and the 95th
percentile of N frames after a warm-up.

With clouds (issue 19): the same frame with the cumulus and stratocumulus presets in
CLOUD_VIEW (bench_viewer.py's and tests/viewer/test_viewer_clouds.py's view), the preview
tables; the cloud message uploaded as tables.js `uploadClouds` does and the wind's columns and
noise origins set as viewer.js `cloudUniforms` does (clouds-NAME.npz); the shadow map placed
as viewer.js places it (transport.air_shadows.map_frame) and drawn once, as the page does for
a still view; the frame by the page's adaptive refinement (viewer.js drawRefinedClouds, its
first spacing from transport.adaptive_pixels.coarse_spacing), and for comparison with every
pixel marched in one pass, with the shadow map drawn again ("map redrawn"), and the PSNR
between the refined and the every-pixel frame.

Where the context offers OpenGL 4.3, the one-pass sky (clear, or every pixel marched through
the clouds) is also timed as a compute shader of the same code (`Frame.compute_sky`): an
H100's or H200's pixel shaders run on two of its TPCs, compute on all of them.

The fast model (issue 21, viewer.js applyFast): a parameter change (the aerosol's amount
alternating x2 and x1) made into an image as fast.js does: the transmittance, multiple-scattering
and ground-irradiance LUTs and the sky-view LUT, one pass a LUT and group of four wavelengths
into a layer of an RGBA16F texture array, then the frame (fast_sky + composite) at 1920 x 1080;
timed as a whole (the change-to-image latency's GPU part), the LUTs alone and the frame alone
(a still view: its sky-view LUT kept), from the description the server sends (`/api/fast`,
fast-NAME.npz), for each of FAST_ATMOSPHERES (the particles' factor changed; each in the view
at its own radius); `--fast-only` times only these.

The viewer shows one atmosphere at a time; "one more atmosphere on screen" is measured as a
second sky pass from a second, separately uploaded copy of the same tables, added into the same
target (what drawing a second body's atmosphere over the first would cost at full screen).

Two steps, so that the GPU machine needs neither skyscatter's dependencies nor its tables:

  1. where skyscatter runs (the full Earth tables come from the table cache, computed first
     when missing: about a minute on 2 cores):
       PYTHONPATH=src python benchmarks/bench_viewer_gpu.py prepare --out .bench_gpu
     writes .bench_gpu/earth-full.npz and earth-preview.npz (the decoded table message and the
     view's uniforms: bench_viewer.py's view, 2 m above ground at 45 deg N, sun zenith 60 deg),
     clouds-NAME.npz and fast-NAME.npz (the fast model's descriptions);
  2. on the GPU machine (numpy and moderngl only):
       python benchmarks/bench_viewer_gpu.py run --tables .bench_gpu [--frames 500]
     prints the GL renderer and driver and one line per case; --png DIR saves the frames.

moderngl (and its glcontext) is a benchmark-only install (`pip install moderngl`), not a
skyscatter dependency; it needs an EGL driver (libEGL from glvnd and the GPU vendor's EGL).
"""

from __future__ import annotations

import argparse
import json
import time
from functools import partial
from pathlib import Path

import numpy as np

STATIC = Path(__file__).resolve().parents[1] / "src" / "skyscatter" / "viewer" / "static"
# viewer.js: PREFIX, LIBRARY, FULL_SCREEN and the sources of the "sky" and "composite" programs
PREFIX = ("#version 300 es\nprecision highp float;\nprecision highp int;\n"
          "precision highp sampler3D;\n")
FULL_SCREEN = "in vec2 position;\nvoid main() { gl_Position = vec4(position, 0.0, 1.0); }\n"
LIBRARY = ["generated/constants.glsl", "shaders/parameterisation.glsl", "shaders/camera.glsl",
           "shaders/sky.glsl", "shaders/tonemap.glsl"]
CLOUDY = [*LIBRARY, "shaders/clouds.glsl"]
SKY = [*CLOUDY, "shaders/main.frag"]
# viewer.js PROGRAMS: (fragment sources, defines, vertex source; None: FULL_SCREEN)
PROGRAMS = {"sky": (SKY, "", None), "cloudy_sky": (SKY, "#define CLOUDS\n", None),
            "cloud_final": (SKY, "#define CLOUDS\n#define CLOUDS_REFINED\n", None),
            "cloud_map": ([*CLOUDY, "shaders/cloud_map.frag"], "", None),
            "cloud_behind": ([*CLOUDY, "shaders/cloud_behind.frag"], "", None),
            "cloud_settle": ([*CLOUDY, "shaders/cloud_level.frag"], "#define CLOUD_SETTLE\n",
                             None),
            "cloud_level": ([*CLOUDY, "shaders/cloud_level.frag"], "", None),
            "cloud_scatter": (["shaders/cloud_scatter.frag"], "", "shaders/cloud_scatter.vert"),
            "composite": (["generated/constants.glsl", "shaders/tonemap.glsl",
                           "shaders/composite.frag"], "", None),
            "fast_sky": ([*CLOUDY, "shaders/fast_model.glsl", "shaders/main.frag"],
                         "#define FAST_MODEL\n", None),
            **{f"fast_{lut}": ([*LIBRARY, "shaders/fast_model.glsl", f"shaders/fast_{lut}.frag"],
                               "", None)
               for lut in ("transmittance", "multiple", "irradiance", "sky_view")}}
# fast.js: the LUTs in the order `compute` makes them (the sky-view last, `skyView`), texture
# units of its samplers, the LUT sizes (lut_layout.json "fast")
FAST_LUTS = ("transmittance", "multiple", "irradiance", "sky_view")
FAST_UNITS = {"u_fast_transmittance": 0, "u_fast_multiple": 1, "u_fast_sky_view": 2,
              "u_fast_density": 3, "u_fast_phase": 4, "u_fast_irradiance": 5}
LAYOUT = STATIC / "generated" / "lut_layout.json"
# the fast model's atmospheres: Earth (the PSNR against its tables), Mars's Mie dust, and the
# fog's 13 335 density levels (the largest description)
FAST_ATMOSPHERES = ("earth", "mars-physical", "earth-fog")
# bench_viewer.py's VIEW and the page's defaults (controls.js NUMBERS)
VIEW = {"sun_zenith": 60.0, "sun_azimuth": 200.0, "heading": 180.0, "pitch": 10.0,
        "roll": 0.0, "fov": 60.0, "fisheye_fov": 180.0, "altitude_m": 2.0, "lat": 45.0,
        "lon": 0.0, "ev100": 13.0, "operator": "aces"}
# bench_viewer.py's CLOUD_VIEW: the clouds' time 600 s
CLOUD_VIEW = dict(VIEW, sun_zenith=35.0, sun_azimuth=160.0, heading=150.0, pitch=12.0, fov=75.0,
                  ev100=13.5, cloud_time_s=600.0)
CLOUD_PRESETS = ("cumulus", "stratocumulus")
CLOUD_CASES = (("perspective", 1920, 1080), ("perspective", 1280, 720))
CLOUD_UNITS = ("noise", "profiles", "phase", "optics")  # texture units 4-7 (viewer.js)
MAP_UNITS = ("low", "middle", "high")  # texture units 8-10: the clouds' shadow map (viewer.js)
CASES = (("perspective", 1920, 1080), ("fisheye", 1080, 1080))
CASE_DRAWS = (("sky pass", 1, False), ("frame (sky + composite)", 1, True),  # atmospheres,
              ("frame, 2 atmospheres", 2, True))                           # composite pass


def prepare(out: Path, cache_dir: str | None) -> None:
    """Write out/earth-{full,preview}.npz: the table message the server sends, decoded, and
    the view's uniforms that do not depend on the image size (viewer.js viewUniforms)."""
    from skyscatter.disk_cache import TableCache, default_cache_directory
    from skyscatter.render.camera import _basis
    from skyscatter.render.scene import orbit_viewpoint, sun_direction
    from skyscatter.render.tonemap import OPERATORS, exposure_scale
    from skyscatter.viewer.gpu_tables import decode
    from skyscatter.viewer.table_service import TableRequest, TableService

    cache = TableCache(cache_dir or default_cache_directory())
    service = TableService(cache=cache, log=print)
    out.mkdir(parents=True, exist_ok=True)

    def view_uniforms(v: dict, radius: float) -> tuple[dict, object]:
        site = orbit_viewpoint(v["altitude_m"], v["lat"], v["lon"], radius)
        right, up, forward = _basis(*np.radians([v["heading"], v["pitch"], v["roll"]]))
        return {
            "u_tan_half_fov": float(np.tan(np.radians(v["fov"]) / 2)),
            "u_camera_basis": np.concatenate([right, up, forward]).tolist(),
            "u_fisheye_theta_max": float(np.radians(v["fisheye_fov"]) / 2),
            "u_local_to_world": site.to_world.T.reshape(-1).tolist(),  # columns
            "u_camera_position": site.position_m.tolist(),
            "u_sun_direction": site.direction_to_world(
                sun_direction(v["sun_zenith"], v["sun_azimuth"])).tolist(),
            "u_exposure": exposure_scale(v["ev100"]),
            "u_operator": list(OPERATORS).index(v["operator"]),
        }, site

    for quality in ("full", "preview"):
        start = time.perf_counter()
        message = service.tables(TableRequest("earth", (), None, quality))
        tables = decode(message)
        header = tables.header
        view, _ = view_uniforms(VIEW, header["bottom_radius_m"])
        np.savez(out / f"earth-{quality}.npz", header=json.dumps(header), view=json.dumps(view),
                 message_bytes=len(message), **tables.arrays)
        print(f"{quality}: {len(message) / 2**20:.1f} MiB message, scattering "
              f"{header['scattering_shape']}, {header['n_wavelengths']} wavelengths, "
              f"{header['orders']} orders ({time.perf_counter() - start:.1f} s)")
    from skyscatter.viewer.cloud_service import CloudService
    from skyscatter.viewer.gpu_clouds import decode_clouds
    clouds = CloudService(service)
    for name in CLOUD_PRESETS:
        message = clouds.message(name, "earth")
        gpu = decode_clouds(message)
        view, site = view_uniforms(CLOUD_VIEW, gpu.header["bottom_radius_m"])
        params, uniforms = _cloud_uniforms(gpu, site, CLOUD_VIEW["cloud_time_s"])
        arrays = {f"cloud_{key}": value for key, value in gpu.arrays.items()}
        arrays["cloud_params"] = params
        np.savez(out / f"clouds-{name}.npz", header=json.dumps(gpu.header),
                 view=json.dumps(view), clouds=json.dumps(uniforms), message_bytes=len(message),
                 map=json.dumps(_map_uniforms(params, site, view)),
                 spacing=json.dumps(_spacings(site)), **arrays)
        print(f"clouds {name}: {len(message) / 2**20:.1f} MiB message")
    from skyscatter.viewer.gpu_fast import decode_fast
    for name in FAST_ATMOSPHERES:
        message = service.fast_message(name)
        header, arrays = decode_fast(message)
        view, _ = view_uniforms(VIEW, header["bottom_radius_m"])
        np.savez(out / f"fast-{name}.npz", header=json.dumps(header), view=json.dumps(view),
                 message_bytes=len(message), **arrays)
        print(f"fast model {name}: {len(message) / 2**10:.1f} KiB description, "
              f"{header['groups']} groups, {header['altitudes']} density levels")


def _cloud_uniforms(gpu, site, seconds: float) -> tuple[np.ndarray, dict]:
    """viewer.js `cloudUniforms` for an observer `site` (its frame east, north, up) at the
    clouds' time `seconds`: the parameter table with the wind's columns, the noise origins."""
    from skyscatter.atmosphere import _cloud_sampling as columns
    from skyscatter.atmosphere.cloud_config import MAX_CLOUD_LAYERS
    from skyscatter.viewer.codegen import cloud_param_vec4s

    params = np.array(gpu.arrays["params"], dtype=np.float64)
    n = gpu.header["texture_size"]
    origins = np.zeros((3 * MAX_CLOUD_LAYERS, 3))
    east, north = site.to_world[:, 0], site.to_world[:, 1]
    for layer, (wind_east, wind_north) in enumerate(gpu.header["wind_enu_m_s"]):
        row = params[layer]
        wind = east * wind_east + north * wind_north
        speed = float(np.linalg.norm(wind))
        along = wind / speed if speed > 0 else east
        offset = wind * seconds
        row[columns.OFFSET_X:columns.OFFSET_X + 3] = offset
        row[columns.ALONG_X:columns.ALONG_X + 3] = along
        stretch = row[columns.STRETCH_MINUS_ONE]
        c = site.position_m - offset
        m = c - (c @ along) * stretch / (1 + stretch) * along
        tile = row[columns.INV_SCALE] * n
        origins[3 * layer] = np.mod(m * tile, n)
        origins[3 * layer + 1] = np.mod(m[[2, 0, 1]] * tile / columns.COVERAGE_TILE_RATIO, n)
        origins[3 * layer + 2] = np.mod(m * row[columns.INV_DETAIL_SCALE] * n, n)
    packed = np.zeros((MAX_CLOUD_LAYERS, 4 * cloud_param_vec4s()))
    packed[:len(params)] = params[:, :packed.shape[1]]
    return params.astype(np.float32), {
        "u_cloud_layers": int(gpu.header["n_layers"]), "u_cloud_texture_size": float(n),
        "u_cloud_params": packed.reshape(-1).astype(np.float32).tolist(),
        "u_cloud_origin": origins.reshape(-1).tolist(),
        "u_cloud_ground_shade": list(gpu.header["ground_shade_xyz"])}


def _map_uniforms(params: np.ndarray, site, view: dict) -> dict:
    """viewer.js `drawCloudMap`'s uniforms of the shadow map for CLOUD_VIEW (a 16:9 image):
    transport.air_shadows.map_frame over the rays of a 192 x 108 image (the page: 17 x 17)."""
    from skyscatter.atmosphere import _cloud_sampling as columns
    from skyscatter.render.camera import PerspectiveCamera
    from skyscatter.transport.air_shadows import SHADOW_MAX_M, map_frame, shaded_stretch

    v = CLOUD_VIEW
    local, _ = PerspectiveCamera(192, 108, v["fov"], heading_deg=v["heading"],
                                 pitch_deg=v["pitch"]).directions()
    rays = site.direction_to_world(local.reshape(-1, 3))
    low, high = float(params[:, columns.BASE_R].min()), float(params[:, columns.TOP_R].max())
    origin = np.asarray(view["u_camera_position"])
    sun = np.asarray(view["u_sun_direction"])
    stretch = shaded_stretch(origin, rays, np.full(len(rays), np.inf),
                             float(np.linalg.norm(origin) - v["altitude_m"]), high)
    frame = map_frame(low, high, rays, stretch, sun)
    assert frame is not None and stretch[:, 1].max() <= SHADOW_MAX_M + 1.0
    return {"u_map_on": 1, "u_map_e1": frame.e1.tolist(), "u_map_e2": frame.e2.tolist(),
            "u_map_corner": frame.corner.tolist(), "u_map_texel": frame.texel,
            "u_map_size": list(frame.shape),
            "u_map_levels": [low, float(frame.levels[1] - frame.levels[0])]}


def _spacings(site) -> dict:
    """viewer.js drawRefinedClouds' first spacing for CLOUD_VIEW at each size of CLOUD_CASES
    (transport.adaptive_pixels.coarse_spacing of the CPU camera's rays)."""
    from skyscatter.render.camera import PerspectiveCamera
    from skyscatter.transport.adaptive_pixels import coarse_spacing

    spacings = {}
    for _, width, height in CLOUD_CASES:
        camera = PerspectiveCamera(width, height, CLOUD_VIEW["fov"],
                                   heading_deg=CLOUD_VIEW["heading"],
                                   pitch_deg=CLOUD_VIEW["pitch"])
        local, _ = camera.directions()
        pixels = np.arange(width * height).reshape(height, width)
        spacings[f"{width}x{height}"] = coarse_spacing(local.reshape(-1, 3), pixels)
    return spacings


# The sky pass as a compute shader (`Frame.compute_sky`): main.frag's main() called per image
# pixel, its output stored in the float frame (RGBA16F)
COMPUTE_MAIN = """
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba16f, binding = 0) uniform writeonly highp image2D u_image;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= int(u_resolution.x) || p.y >= int(u_resolution.y)) return;
    frag_coord = vec4(vec2(p) + 0.5, 0.0, 1.0);
    fragment_main();
    imageStore(u_image, p, frag_colour);
}
"""


def _compute_source(names: list[str], defines: str) -> str:
    """The fragment program of `names` as desktop GLSL 4.30 compute: main.frag's output a
    variable, its main() `fragment_main`, gl_FragCoord the pixel's centre."""
    text = (_source(names).replace("out vec4 frag_colour;", "vec4 frag_colour;")
            .replace("void main()", "void fragment_main()").replace("gl_FragCoord", "frag_coord"))
    prefix = PREFIX.replace("#version 300 es", "#version 430")
    return prefix + "vec4 frag_coord;\n" + defines + text + COMPUTE_MAIN


def _source(names: list[str]) -> str:
    return "\n".join((STATIC / name).read_text() for name in names)


class Frame:
    """The viewer's sky and composite programs and one set of uploaded tables per atmosphere,
    drawing Viewer.draw's frame into off-screen targets (`resize`)."""

    def __init__(self, ctx, tables: list[dict]) -> None:
        self.ctx = ctx
        self.version_line = "#version 300 es"
        self.programs = {
            key: self._program(defines + _source(names),
                               FULL_SCREEN if vertex is None else _source([vertex]))
            for key, (names, defines, vertex) in PROGRAMS.items()}
        quad = ctx.buffer(np.array([-1, -1, 3, -1, -1, 3], dtype="f4").tobytes())
        self.quads = {key: ctx.vertex_array(program, [(quad, "2f", "position")])
                      for key, program in self.programs.items() if key != "cloud_scatter"}
        self.points = ctx.vertex_array(self.programs["cloud_scatter"], [])
        self.refined = True  # clouds by the adaptive refinement (viewer.js), else every pixel
        self.compute = {}  # compute shaders of `compute_sky`
        self.tables = [self._upload(t) for t in tables]
        self.clouds = self._upload_clouds(None)
        self.map = None  # the clouds' shadow map (`set_clouds`)
        self.view = None  # the tables' view; the clouds' own with clouds (`set_clouds`)
        self.fast = None  # the fast model drawing the sky instead of the tables (FastModel)

    def set_clouds(self, data: dict | None) -> None:
        """Draw `data`'s clouds (a clouds-NAME.npz, loaded) in its view, or none; with clouds,
        the shadow map's targets (viewer.js drawCloudMap: three RGBA16F textures, linear)."""
        self.clouds = self._upload_clouds(data)
        self.view = None if data is None else data["view"]
        self.map = None
        if data is not None:
            n_u, n_w = data["map"]["u_map_size"]
            self.map = self._float_targets((n_u, n_w * data["header"]["n_layers"]),
                                           len(MAP_UNITS), dtype="f2", linear=True)
            self.map["uniforms"] = data["map"]
            self.spacings = data["spacing"]

    def draw_map(self) -> None:
        """Viewer.drawCloudMap: cloud_map.frag, one pass a layer into its rows of the map."""
        program = self.programs["cloud_map"]
        self._bind_clouds(program)
        view = self.view
        self._set(program, {**self.map["uniforms"], "u_camera_position": view["u_camera_position"],
                            "u_sun_direction": view["u_sun_direction"]})
        self.map["framebuffer"].use()
        n_u, n_w = self.map["uniforms"]["u_map_size"]
        for layer in range(self.clouds["uniforms"]["u_cloud_layers"]):
            self.ctx.viewport = (0, layer * n_w, n_u, n_w)
            program["u_map_layer"].value = layer
            self.quads["cloud_map"].render(vertices=3)

    def _bind_clouds(self, program) -> None:
        """Viewer.bindClouds: the cloud textures on units 4-8 and their uniforms."""
        for unit, name in enumerate(CLOUD_UNITS, start=4):
            self.clouds["textures"][name].use(location=unit)
            self._set(program, {f"u_cloud_{name}": unit})  # the map pass reads only some
        self._set(program, self.clouds["uniforms"])

    def resize(self, width: int, height: int) -> None:
        """Targets of w x h: the float frame (RGBA16F, as Viewer.target) and the canvas (RGBA8)."""
        import moderngl

        self.width, self.height = width, height
        self.frame = self.ctx.texture((width, height), 4, dtype="f2")
        self.frame.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.frame_buffer = self.ctx.framebuffer([self.frame])
        self.screen = self.ctx.framebuffer([self.ctx.renderbuffer((width, height), 4)])
        if self.map is not None:  # viewer.js drawRefinedClouds' targets and first spacing
            self.spacing = self.spacings[f"{width}x{height}"]
            grid = (-(-width // 2), -(-height // 2)) if self.spacing > 1 else (width, height)
            self.refine_targets = [self._float_targets((width, height), 1),
                                   self._float_targets((width, height), 2),
                                   self._float_targets(grid, 2, depth=True)]

    def _float_targets(self, size: tuple[int, int], count: int, *, dtype: str = "f4",
                       linear: bool = False, depth: bool = False) -> dict:
        """viewer.js textureTargets: `count` RGBA textures of `size` (float32, or `dtype`;
        nearest, or `linear` filtering; edges clamped), one framebuffer (with a depth buffer if
        `depth`)."""
        import moderngl

        textures = [self.ctx.texture(size, 4, dtype=dtype) for _ in range(count)]
        filtering = moderngl.LINEAR if linear else moderngl.NEAREST
        for texture in textures:
            texture.filter = (filtering, filtering)
            texture.repeat_x = texture.repeat_y = False
        buffer = self.ctx.depth_renderbuffer(size) if depth else None
        return {"textures": textures, "framebuffer": self.ctx.framebuffer(textures, buffer)}

    def _program(self, fragment: str, vertex: str):
        """Compiles as the page does; NVIDIA's desktop GL takes `#version 300 es` under
        ARB_ES3_compatibility, else the version line becomes desktop GLSL 3.30 (here only)."""
        import moderngl

        try:
            return self.ctx.program(vertex_shader=PREFIX + vertex,
                                    fragment_shader=PREFIX + fragment)
        except moderngl.Error:
            self.version_line = "#version 330 core"
            prefix = PREFIX.replace("#version 300 es", self.version_line)
            return self.ctx.program(vertex_shader=prefix + vertex,
                                    fragment_shader=prefix + fragment)

    def _upload(self, data: dict) -> dict:
        """tables.js uploadTables: RGB16F textures, linear (nearest for the phase texture)."""
        import moderngl

        header = data["header"]
        n_r, n_mu, n_mu_s, n_nu, n_t = header["scattering_shape"]
        textures = {}
        for name, filtering in (("transmittance", moderngl.LINEAR),
                                ("irradiance", moderngl.LINEAR), ("phase", moderngl.NEAREST)):
            array = data[name]
            texture = self.ctx.texture((array.shape[1], array.shape[0]), 3, array.tobytes(),
                                       dtype="f2", alignment=1)
            texture.filter = (filtering, filtering)
            texture.repeat_x = texture.repeat_y = False
            textures[name] = texture
        scattering = self.ctx.texture3d((n_nu * n_mu_s, n_mu, n_t * n_r), 3,
                                        data["scattering"].tobytes(), dtype="f2", alignment=1)
        scattering.filter = (moderngl.LINEAR, moderngl.LINEAR)
        scattering.repeat_x = scattering.repeat_y = scattering.repeat_z = False
        textures["scattering"] = scattering
        scales = header["scales"]
        uniforms = {
            "u_transmittance_size": tuple(data["transmittance"].shape[1::-1]),
            "u_irradiance_size": tuple(data["irradiance"].shape[1::-1]),
            "u_scattering_shape": (n_r, n_mu, n_mu_s, n_nu), "u_n_tables": n_t,
            "u_phase_angles": header["phase_angles"], "u_phase_rows": header["phase_rows"],
            "u_transmittance_scale": scales["transmittance"],
            "u_irradiance_scale": scales["irradiance"], "u_phase_scale": scales["phase"],
            "u_scattering_scales": scales["scattering"],
            "u_bottom_radius": header["bottom_radius_m"], "u_top_radius": header["top_radius_m"],
            "u_mu_s_min": header["mu_s_min"], "u_sun_angle_share": header["sun_angle_share"],
            "u_ground_albedo": header["ground_albedo_xyz"],
            "u_sun_irradiance": header["sun_irradiance_xyz"],
            "u_sun_angular_radius": header["sun_angular_radius_rad"],
            "u_sun_solid_angle": header["sun_solid_angle_sr"],
            "u_sun_disk": np.asarray(header["sun_disk_xyz"]).reshape(-1),
            "u_radius_warp": list(header["radius_warp"]),  # vec4 array, zero-padded (tables.js)
            "u_radius_warp_identity": int(header.get("radius_warp_identity", False)),
        }
        return {"textures": textures, "uniforms": uniforms, "view": data["view"]}

    def _upload_clouds(self, data: dict | None) -> dict:
        """tables.js uploadClouds: the noise RG16F (REPEAT across, its depth clamped), the rest
        float32 read with texelFetch; 1-texel stand-ins without clouds."""
        import moderngl

        ctx = self.ctx
        if data is None:
            noise = ctx.texture3d((1, 1, 1), 2, np.zeros(2, "f2").tobytes(), dtype="f2")
            flat = {key: np.zeros((1, 1, width), "f4") for key, width in
                    (("profiles", 2), ("phase", 3), ("optics", 3))}
            uniforms = {"u_cloud_layers": 0, "u_cloud_texture_size": 1.0,
                        "u_cloud_ground_shade": [1.0, 1.0, 1.0]}
        else:
            header = data["header"]
            depth, height, width, _ = data["cloud_noise"].shape
            noise = ctx.texture3d((width, height, depth), 2, data["cloud_noise"].tobytes(),
                                  dtype="f2", alignment=1)
            optics = np.stack([np.asarray(header[key], "f4") for key in (
                "mass_extinction_xyz_m2_g", "single_scattering_albedo_xyz", "asymmetry_xyz")],
                axis=1)  # (layers, 3, 3)
            flat = {"profiles": data["cloud_profiles"], "phase": data["cloud_phase"],
                    "optics": optics}
            uniforms = data["clouds"]
        noise.filter = (moderngl.LINEAR, moderngl.LINEAR)
        noise.repeat_x = noise.repeat_y = True
        noise.repeat_z = False
        textures = {"noise": noise}
        for key, array in flat.items():
            array = np.ascontiguousarray(array, dtype="f4")
            texture = ctx.texture((array.shape[1], array.shape[0]), array.shape[2],
                                  array.tobytes(), dtype="f4", alignment=1)
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            textures[key] = texture
        return {"textures": textures, "uniforms": uniforms}

    def _set(self, program, values: dict) -> None:
        """viewer.js setUniforms: arrays and matrices as written, the rest by value."""
        for name, value in values.items():
            uniform = program.get(name, None)
            if uniform is None:
                continue  # optimised out (viewer.js: location null)
            if uniform.array_length > 1 or uniform.dimension > 4:  # arrays, matrices
                flat = np.zeros(uniform.array_length * uniform.dimension, dtype="f4")
                flat[:len(value)] = value
                uniform.write(flat.tobytes())
            else:
                uniform.value = tuple(value) if isinstance(value, (list, tuple)) else value

    def compute_sky(self, tables: dict, projection: int) -> None:
        """`draw_sky`'s one pass (the clear sky, or every pixel marched through the clouds) as
        a compute shader into the float frame: the same code on all of a GPU's
        multiprocessors, where an H100's or H200's pixel shaders run on two of its TPCs
        (NVIDIA H100 Tensor Core GPU Architecture whitepaper, 2022)."""
        key = "sky" if self.map is None else "cloudy_sky"
        if key not in self.compute:
            names, defines, _ = PROGRAMS[key]
            self.compute[key] = self.ctx.compute_shader(_compute_source(names, defines))
        program = self._setup(key, tables, projection, self.compute[key])
        self.frame.bind_to_image(0, read=False, write=True)
        program.run(-(-self.width // 8), -(-self.height // 8))

    def _setup(self, key: str, tables: dict, projection: int, program=None):
        """viewer.js drawSky's bindings for program `key` (or the compute `program`): tables,
        clouds, shadow map, view."""
        program = self.programs[key] if program is None else program
        for unit, name in enumerate(("transmittance", "irradiance", "scattering", "phase")):
            tables["textures"][name].use(location=unit)
            self._set(program, {f"u_{name}": unit})
        self._set(program, tables["uniforms"])
        if self.map is not None:
            self._bind_clouds(program)
            textures = zip(MAP_UNITS, self.map["textures"], strict=True)
            for unit, (name, texture) in enumerate(textures, start=8):
                texture.use(location=unit)
                self._set(program, {f"u_cloud_map_{name}": unit})
            self._set(program, self.map["uniforms"])
        self._set_view(program, projection, tables)
        return program

    def view_of(self, tables: dict | None) -> dict:
        """The view's uniforms: the clouds' view, else that of `tables` (or the first's)."""
        if self.view is not None:
            return self.view
        return (self.tables[0] if tables is None else tables)["view"]

    def _set_view(self, program, projection: int, tables: dict | None) -> None:
        """viewer.js viewUniforms for this target's size, output "exposed"."""
        view = dict(self.view_of(tables))
        tan_v = view.pop("u_tan_half_fov")
        self._set(program, {**view, "u_resolution": (self.width, self.height),
                            "u_projection": projection, "u_output": 2,  # OUTPUT_EXPOSED
                            "u_half_extent": (tan_v * self.width / self.height, tan_v)})

    def _bind_refinement(self, program, samplers: list) -> None:
        """viewer.js bindRefinement: (name, texture) pairs on units 11-13."""
        for unit, (name, texture) in enumerate(samplers, start=11):
            texture.use(location=unit)
            self._set(program, {name: unit})

    def draw_sky(self, tables: dict, projection: int) -> None:
        """Viewer.drawSky(w, h, "exposed") with `tables` bound (into the bound target)."""
        if self.fast is not None:
            self.fast.draw(projection)
            return
        if self.map is None or not self.refined:
            key = "sky" if self.map is None else "cloudy_sky"
            self._setup(key, tables, projection)
            self.quads[key].render(vertices=3)
            return
        target = self.ctx.fbo
        behind, known = self.draw_refined(tables, projection)
        target.use()
        program = self._setup("cloud_final", tables, projection)
        self._bind_refinement(program, [("u_behind", behind["textures"][0]),
                                        ("u_known_t", known["textures"][0]),
                                        ("u_known_a", known["textures"][1])])
        self.quads["cloud_final"].render(vertices=3)

    def draw_refined(self, tables: dict, projection: int) -> tuple[dict, dict]:
        """Viewer.drawRefinedClouds: the radiance behind the clouds, the lattice and the levels
        (cloud_level.frag, cloud_scatter); returns the behind and known targets."""
        import moderngl

        width, height = self.width, self.height
        behind, known, level = self.refine_targets
        behind["framebuffer"].use()
        self._setup("cloud_behind", tables, projection)
        self.quads["cloud_behind"].render(vertices=3)
        spacing = self.spacing
        passes = [(spacing, 0, 0)]
        half = spacing // 2
        while half >= 1:
            passes += [(spacing, 0, half), (spacing, half, 0), (spacing, half, half)]
            spacing, half = half, half // 2
        ctx = self.ctx
        for index, (step, dy, dx) in enumerate(passes):
            columns, rows = -(-(width - dx) // step), -(-(height - dy) // step)
            level["framebuffer"].use()
            level["framebuffer"].depth_mask = True
            level["framebuffer"].clear(depth=1.0)  # 1: every pixel left to march
            ctx.viewport = (0, 0, columns, rows)
            ctx.enable(moderngl.DEPTH_TEST)
            keys = ("cloud_settle", "cloud_level") if index else ("cloud_level",)
            for key in keys:  # the settled pixels at depth 0, the rest marched at depth 0.5
                program = self._setup(key, tables, projection)
                self._bind_refinement(program, [("u_behind", behind["textures"][0]),
                                                ("u_known_t", known["textures"][0]),
                                                ("u_known_a", known["textures"][1])])
                program["u_level"].value = (step, dy, dx)
                ctx.depth_func = "1" if key == "cloud_settle" else "<"
                level["framebuffer"].depth_mask = key == "cloud_settle"
                self.quads[key].render(vertices=3)
            level["framebuffer"].depth_mask = True
            ctx.disable(moderngl.DEPTH_TEST)
            known["framebuffer"].use()
            scatter = self.programs["cloud_scatter"]
            self._bind_refinement(scatter, [("u_level_t", level["textures"][0]),
                                            ("u_level_a", level["textures"][1])])
            self._set(scatter, {"u_level": (step, dy, dx), "u_level_columns": columns,
                                "u_resolution": (width, height)})
            self.points.render(moderngl.POINTS, vertices=columns * rows)
        return behind, known

    def draw(self, projection: int, atmospheres: int, composite: bool = True) -> None:
        """Viewer.draw: the sky of `atmospheres` table sets (added) into the float frame, then
        the composite into the RGBA8 target."""
        import moderngl

        self.frame_buffer.use()
        for index in range(atmospheres):
            if index == 1:
                self.ctx.enable(moderngl.BLEND)
                self.ctx.blend_func = moderngl.ONE, moderngl.ONE
            self.draw_sky(self.tables[index], projection)
        self.ctx.disable(moderngl.BLEND)
        if composite:
            self.screen.use()
            self.frame.use(location=0)
            program = self.programs["composite"]
            program["u_frame"].value = 0
            program["u_operator"].value = self.tables[0]["view"]["u_operator"]
            self.quads["composite"].render(vertices=3)


class FastModel:
    """fast.js FastModel in `frame`'s context: the description's density and phase textures,
    the LUTs as RGBA16F texture arrays (a layer per group) with a framebuffer per layer."""

    def __init__(self, frame: Frame, data: dict) -> None:
        import moderngl

        ctx = frame.ctx
        self.frame = frame
        self.header = header = data["header"]
        self.groups = header["groups"]
        sizes = json.loads(LAYOUT.read_text())["fast"]
        self.max_constituents = sizes["max_constituents"]
        self.max_groups = sizes["max_groups"]
        self.sizes = {lut: tuple(sizes["sizes"][lut]) for lut in FAST_LUTS}
        self.data = {}
        for name, components in (("density", 1), ("phase", 4)):  # tables.js floatTexture
            array = np.ascontiguousarray(data[name], dtype="f4")
            texture = ctx.texture((array.shape[1], array.shape[0]), components, array.tobytes(),
                                  dtype="f4", alignment=1)
            texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self.data[f"u_fast_{name}"] = texture
        self.none = ctx.texture_array((1, 1, 1), 4, dtype="f2")  # bound for the LUT written
        self.luts, self.framebuffers = {}, {}
        attach = _framebuffer_texture_layer()
        for lut in FAST_LUTS:
            width, height = self.sizes[lut]
            array = ctx.texture_array((width, height, self.groups), 4, dtype="f2")
            array.filter = (moderngl.LINEAR, moderngl.LINEAR)
            array.repeat_x = array.repeat_y = False
            self.luts[f"u_fast_{lut}"] = array
            self.framebuffers[lut] = []
            for g in range(self.groups):  # fast.js: framebufferTextureLayer(..., texture, 0, g)
                framebuffer = ctx.framebuffer([ctx.texture((width, height), 4, dtype="f2")])
                framebuffer.use()
                attach(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, array.glo, 0, g)
                self.framebuffers[lut].append(framebuffer)
        to_xyz = np.zeros((self.max_groups * 4, 3), dtype="f4")  # mat4x3 columns C_w E_w
        weights = np.asarray(header["xyz_weights"]) * np.asarray(header["sun_irradiance"])[:, None]
        to_xyz[:len(weights)] = weights
        self.to_xyz = to_xyz.reshape(-1)
        self.amounts: dict = {}

    def uniforms(self, group: int) -> dict:
        """fast.js bind's uniforms: each group's coefficients times the amounts' factors."""
        h = self.header
        extinction = np.zeros((self.max_groups, self.max_constituents, 4), dtype="f4")
        scattering = np.zeros_like(extinction)
        for c, name in enumerate(h["names"]):
            factor = self.amounts.get(name, 1.0)
            extinction[:self.groups, c] = factor * np.reshape(h["extinction_m"][c], (-1, 4))
            scattering[:self.groups, c] = factor * np.reshape(h["scattering_m"][c], (-1, 4))
        albedo = np.zeros((self.max_groups, 4), dtype="f4")
        albedo[:self.groups] = np.reshape(h["ground_albedo"], (-1, 4))
        return {"u_fast_extinction": extinction.reshape(-1), "u_fast_scattering":
                scattering.reshape(-1), "u_fast_albedo": albedo.reshape(-1),
                "u_fast_group": group, "u_fast_groups": self.groups,
                "u_fast_constituents": len(h["names"]), "u_fast_altitudes": h["altitudes"],
                "u_fast_density_rows": h["density_rows"],
                "u_fast_altitude_step": h["altitude_step_m"], "u_fast_to_xyz": self.to_xyz,
                "u_bottom_radius": h["bottom_radius_m"], "u_top_radius": h["top_radius_m"],
                "u_fast_mu_s_centre": h["multiple_scattering_mu_s_centre"],
                "u_sun_irradiance": h["sun_irradiance_xyz"],
                "u_sun_angular_radius": h["sun_angular_radius_rad"],
                "u_sun_solid_angle": h["sun_solid_angle_sr"],
                "u_sun_disk": np.asarray(h["sun_disk_xyz"]).reshape(-1)}

    def bind(self, program, group: int, writing: str | None = None) -> None:
        """fast.js bind: textures on their units (none on the LUT being written), uniforms."""
        textures = {**self.luts, **self.data}
        for name, unit in FAST_UNITS.items():
            (self.none if name == writing else textures[name]).use(location=unit)
            self.frame._set(program, {name: unit})
        self.frame._set(program, self.uniforms(group))

    def pass_(self, lut: str, extra: dict | None = None) -> None:
        """fast.js pass: one pass per group into `lut`."""
        key = f"fast_{lut}"
        program = self.frame.programs[key]
        for g in range(self.groups):
            self.framebuffers[lut][g].use()
            self.frame.ctx.viewport = (0, 0, *self.sizes[lut])
            self.bind(program, g, f"u_fast_{lut}")
            self.frame._set(program, extra or {})
            self.frame.quads[key].render(vertices=3)

    def compute(self, amounts: dict) -> None:
        """fast.js compute (a physical parameter changed), then skyView for the frame's view."""
        self.amounts = dict(amounts)
        for lut in FAST_LUTS[:-1]:
            self.pass_(lut)
        self.sky_view()

    def sky_view(self) -> None:
        """fast.js skyView for the camera of the frame's view."""
        view = self.frame.view_of(None)
        position = np.asarray(view["u_camera_position"])
        r = float(np.linalg.norm(position))
        mu_s = float(position @ np.asarray(view["u_sun_direction"]) / r)
        self.pass_("sky_view", {"u_fast_view_radius": r, "u_fast_view_mu_s": mu_s})

    def draw(self, projection: int) -> None:
        """Viewer.drawSky with the fast model (a view from the ground: fast_sky)."""
        program = self.frame.programs["fast_sky"]
        self.bind(program, 0)
        self.frame._set_view(program, projection, None)
        self.frame.quads["fast_sky"].render(vertices=3)


GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 = 0x8D40, 0x8CE0


def _framebuffer_texture_layer():
    """glFramebufferTextureLayer of the current EGL context (moderngl attaches no layers)."""
    import ctypes

    egl = ctypes.CDLL("libEGL.so.1")
    egl.eglGetProcAddress.restype = ctypes.c_void_p
    egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    address = egl.eglGetProcAddress(b"glFramebufferTextureLayer")
    return ctypes.CFUNCTYPE(None, ctypes.c_uint, ctypes.c_uint, ctypes.c_uint, ctypes.c_int,
                            ctypes.c_int)(address)


def _time(ctx, draw, frames: int, warm_up: int) -> tuple[np.ndarray, np.ndarray]:
    """(GPU ms, wall ms) of `frames` calls of `draw` after `warm_up` untimed ones."""
    query = ctx.query(time=True)
    for _ in range(warm_up):
        draw()
    ctx.finish()
    gpu, wall = np.empty(frames), np.empty(frames)
    for i in range(frames):
        start = time.perf_counter()
        with query:
            draw()
        ctx.finish()
        wall[i] = (time.perf_counter() - start) * 1e3
        gpu[i] = query.elapsed / 1e6
    return gpu, wall


def _load_clouds(path: Path) -> dict:
    with np.load(path) as npz:
        data = {name: npz[name] for name in npz.files
                if name.startswith("cloud_") and name != "clouds"}
        for name in ("header", "view", "clouds", "map", "spacing"):
            data[name] = json.loads(str(npz[name]))
        data["message_bytes"] = int(npz["message_bytes"])
    return data


def _load(path: Path) -> dict:
    with np.load(path) as npz:
        data = {name: npz[name] for name in ("transmittance", "irradiance", "scattering", "phase")}
        data["header"] = json.loads(str(npz["header"]))
        data["view"] = json.loads(str(npz["view"]))
        data["message_bytes"] = int(npz["message_bytes"])
    return data


def run(directory: Path, frames: tuple[int, int], warm_up: tuple[int, int],
        png: Path | None, cloud_presets: tuple[str, ...] = CLOUD_PRESETS, *,
        fast_only: bool = False) -> None:
    """Times every case and prints one line each (the clear and fast-model cases over
    frames[0] after warm_up[0], the cloud cases over frames[1] after warm_up[1]); ends with a
    summary table."""
    import moderngl

    try:  # compute shaders (`Frame.compute_sky`) need OpenGL 4.3
        ctx = moderngl.create_standalone_context(backend="egl", require=430)
    except Exception:  # noqa: BLE001 - any driver's refusal: then without them
        ctx = moderngl.create_standalone_context(backend="egl", require=330)
    compute = ctx.version_code >= 430
    print(f"GL_RENDERER {ctx.info['GL_RENDERER']}; GL_VERSION {ctx.info['GL_VERSION']}")
    rows = []

    def timed(quality: str, image: str, case: str, draw, cloudy: bool = False) -> None:
        gpu, wall = _time(ctx, draw, frames[cloudy], warm_up[cloudy])
        rows.append((quality, image, case, np.median(gpu), np.percentile(gpu, 95),
                     np.median(wall), np.percentile(wall, 95)))
        print(f"{quality} {image} {case}: GPU {rows[-1][3]:.3f} ms (p95 {rows[-1][4]:.3f}), "
              f"wall {rows[-1][5]:.3f} ms (p95 {rows[-1][6]:.3f})")

    _warm_clocks(ctx, _load(directory / "earth-preview.npz"))
    for quality in () if fast_only else ("full", "preview"):
        data = _load(directory / f"earth-{quality}.npz")
        header = data["header"]
        print(f"earth {quality}: {header['n_wavelengths']} wavelengths, scattering "
              f"{header['scattering_shape']}, {data['message_bytes'] / 2**20:.1f} MiB")
        frame = Frame(ctx, [data, data])  # two uploads: the second atmosphere's own textures
        for projection, width, height in CASES:
            frame.resize(width, height)
            index = ["perspective", "fisheye"].index(projection)
            image = f"{projection} {width}x{height}"
            for name, atmospheres, composite in CASE_DRAWS:
                timed(quality, image, name, partial(frame.draw, index, atmospheres, composite))
            if compute:
                compute = _try_compute(partial(timed, quality, image, "sky pass as compute",
                                               partial(frame.compute_sky, frame.tables[0], index)),
                                       frame, index)
            frame.draw(index, 1)
            _check(frame, f"{quality}-{projection}", png)
    _time_fast(directory, ctx, timed, png)
    data = _load(directory / "earth-preview.npz")
    frame = Frame(ctx, [data])
    for name in cloud_presets:
        clouds = _load_clouds(directory / f"clouds-{name}.npz")
        frame.set_clouds(clouds)
        n_u, n_w = clouds["map"]["u_map_size"]
        timed("preview", f"map {n_u}x{n_w}", f"{name}: shadow map", frame.draw_map, True)
        for projection, width, height in CLOUD_CASES:
            frame.resize(width, height)
            image = f"{projection} {width}x{height}"
            frame.refined = False
            timed("preview", image, f"{name}, every pixel", partial(frame.draw, 0, 1), True)
            every_pixel = _screen(frame)
            if compute:
                compute = _try_compute(partial(timed, "preview", image,
                                               f"{name}, every pixel, compute",
                                               partial(frame.compute_sky, frame.tables[0], 0),
                                               True),
                                       frame, 0)
            frame.refined = True
            timed("preview", image, f"{name}, map redrawn", partial(_map_and_frame, frame), True)
            timed("preview", image, f"frame with {name}", partial(frame.draw, 0, 1), True)
            _check(frame, f"clouds-{name}-{width}x{height}", png)
            error = _screen(frame).astype(float) - every_pixel
            print(f"  refined against every pixel marched: PSNR "
                  f"{10 * np.log10(255.0**2 / np.mean(error**2)):.1f} dB")
    print(f"\n{'tables':8s} {'image':22s} {'case':36s} {'GPU median':>10s} {'p95':>7s} "
          f"{'wall median':>11s} {'p95':>7s}  [ms], {frames[0]} frames ({frames[1]} with "
          f"clouds)")
    for row in rows:
        print(f"{row[0]:8s} {row[1]:22s} {row[2]:36s} {row[3]:10.3f} {row[4]:7.3f} "
              f"{row[5]:11.3f} {row[6]:7.3f}")


def _time_fast(directory: Path, ctx, timed, png: Path | None) -> None:
    """The fast model's change-to-image cases (module docstring) for each of FAST_ATMOSPHERES
    prepared, in the view of each's own radius, and for Earth how far its frame lies from the
    preview tables' (the tables the page shows after it)."""
    data = _load(directory / "earth-preview.npz")
    for name in FAST_ATMOSPHERES:
        path = directory / f"fast-{name}.npz"
        if not path.exists():
            print(f"no {path.name}: no fast-model case for {name} (run `prepare` again)")
            continue
        with np.load(path) as npz:
            fast_data = {"density": npz["density"], "phase": npz["phase"],
                         "header": json.loads(str(npz["header"]))}
            view = json.loads(str(npz["view"]))
        frame = Frame(ctx, [data])
        frame.resize(1920, 1080)
        frame.draw(0, 1)
        # the preview tables' picture of Earth's view, for the PSNR below
        tables_image = _screen(frame).astype(float) if name == "earth" else None
        frame.view = view
        frame.fast = fast = FastModel(frame, fast_data)
        changed = fast_data["header"]["names"][-1]  # the particles (aerosol, dust, fog)
        factors = iter(np.resize([2.0, 1.0], 10**6))

        def change(fast=fast, frame=frame, changed=changed, factors=factors) -> None:
            fast.compute({changed: next(factors)})  # a slider moved, then the image
            frame.draw(0, 1)

        image = "perspective 1920x1080"
        timed(f"fast {name}", image, f"change ({changed}) to image", change)
        timed(f"fast {name}", image, "LUTs and sky view",
              partial(fast.compute, {changed: 1.5}))
        fast.compute({})
        timed(f"fast {name}", image, "frame (sky view kept)", partial(frame.draw, 0, 1))
        _check(frame, f"fast-{name}", png)
        if tables_image is not None:
            error = _screen(frame).astype(float) - tables_image
            print(f"  fast model against the preview tables: PSNR "
                  f"{10 * np.log10(255.0**2 / np.mean(error**2)):.1f} dB")


def _warm_clocks(ctx, data: dict, seconds: float = 3.0) -> None:
    """Draws clear 1920 x 1080 frames for `seconds` before anything is timed: an idle GPU
    clocks down, and the first case timed on cold clocks took up to 6 times its time."""
    frame = Frame(ctx, [data])
    frame.resize(1920, 1080)
    end = time.perf_counter() + seconds
    while time.perf_counter() < end:
        frame.draw(0, 1)
        ctx.finish()


def _try_compute(time_it, frame: Frame, projection: int) -> bool:
    """Times a compute case and compares it with the fragment pass; False (no more compute
    cases) where the driver does not take the compute shader."""
    import moderngl

    try:
        time_it()
    except moderngl.Error as error:
        print(f"  no compute cases: {str(error)[:300]}")
        return False
    _compare_compute(frame, projection)
    return True


def _compare_compute(frame: Frame, projection: int) -> None:
    """Prints how far the compute pass's float frame lies from the fragment pass's."""
    frame.frame_buffer.use()
    frame.draw_sky(frame.tables[0], projection)
    fragment = np.frombuffer(frame.frame.read(), dtype="f2").astype(float)
    frame.compute_sky(frame.tables[0], projection)
    frame.ctx.finish()
    computed = np.frombuffer(frame.frame.read(), dtype="f2").astype(float)
    largest = np.abs(computed - fragment).max() / np.abs(fragment).max()
    print(f"  compute against fragment: largest difference {largest:.2e} of the largest value")


def _map_and_frame(frame: Frame) -> None:
    """A frame whose view, sun or clouds moved: the shadow map drawn again, then the frame."""
    frame.draw_map()
    frame.draw(0, 1)


def _screen(frame: Frame) -> np.ndarray:
    """The canvas (h, w, 3) uint8, top row first."""
    shown = np.frombuffer(frame.screen.read(components=4), dtype="u1")
    return shown.reshape(frame.height, frame.width, 4)[::-1, :, :3]


def _check(frame: Frame, name: str, png: Path | None) -> None:
    """Prints what the frame holds (a wrong upload shows as NaN, black or saturated pixels);
    saves it as PNG under `png`."""
    exposed = np.frombuffer(frame.frame.read(), dtype="f2").reshape(frame.height, frame.width, 4)
    shown = np.frombuffer(frame.screen.read(components=4), dtype="u1")
    shown = shown.reshape(frame.height, frame.width, 4)[::-1]
    inside = exposed[..., 3] > 0
    finite = np.isfinite(exposed[inside][:, :3]).all(axis=1)
    print(f"  {name}: {inside.mean():.3f} of pixels inside, {1 - finite.mean():.2e} not finite; "
          f"exposed sRGB mean {exposed[inside][finite][:, :3].astype('f8').mean(axis=0).round(4)}"
          f"; 8-bit mean {shown[..., :3].reshape(-1, 3).mean(axis=0).round(1)}")
    if png is not None:
        from PIL import Image

        png.mkdir(parents=True, exist_ok=True)
        Image.fromarray(np.ascontiguousarray(shown[..., :3])).save(png / f"{name}.png")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    step = commands.add_parser("prepare", help="write the tables and view (needs skyscatter)")
    step.add_argument("--out", type=Path, default=Path(".bench_gpu"))
    step.add_argument("--cache-dir", default=None, help="table cache (default: skyscatter's)")
    step = commands.add_parser("run", help="time the frames (needs moderngl and a GPU)")
    step.add_argument("--tables", type=Path, default=Path(".bench_gpu"))
    step.add_argument("--frames", type=int, default=500)
    step.add_argument("--warm-up", type=int, default=50)
    step.add_argument("--cloud-frames", type=int, default=12,
                      help="frames of each cloud case (up to a second each on an H200)")
    step.add_argument("--cloud-warm-up", type=int, default=2)
    step.add_argument("--no-clouds", action="store_true", help="leave the cloud cases out")
    step.add_argument("--fast-only", action="store_true",
                      help="only the fast model's cases (no clear-sky or cloud frames)")
    step.add_argument("--png", type=Path, default=None, help="save each case's frame here")
    args = parser.parse_args()
    if args.command == "prepare":
        prepare(args.out, args.cache_dir)
    else:
        run(args.tables, (args.frames, args.cloud_frames), (args.warm_up, args.cloud_warm_up),
            args.png, () if args.no_clouds or args.fast_only else CLOUD_PRESETS,
            fast_only=args.fast_only)


if __name__ == "__main__":
    main()
