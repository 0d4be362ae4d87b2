"""The figures of `skyscatter compare` (`validate.technique_comparison`): the error against
the Monte Carlo reference per solver and sun zenith, and the solvers' fisheye skies side by side
with their false-colour log ratio to a reference render.

A Monte Carlo fisheye would take hours, so the images' reference is the first solver of the
run ("lut" by default), whose own distance from the Monte Carlo is in the tables beside; the
false colour is log2(Y / Y_reference) of the luminance, -1 (half) blue to +1 (double) red.

Public names: `error_figure`, `fisheye_figure`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from skyscatter.atmosphere.model import Atmosphere
from skyscatter.render.camera import FisheyeCamera
from skyscatter.render.exposure import display_rgb8, metered_ev100
from skyscatter.render.scene import ground_viewpoint, render_sky
from skyscatter.spectrum.colour import spectral_to_xyz, xyz_to_rgb
from skyscatter.transport.geometry import local_frame_directions
from skyscatter.validate.plots import new_figure, save_figure
from skyscatter.validate.report import Figure

__all__ = ["error_figure", "fisheye_figure"]

LOG2_RANGE = 1.0  # the false colour's ends: half and double the reference's luminance


def _worst_band(case, q: float) -> float:
    """The largest q-th percentile of |L / L_MC - 1| of any band [-]; NaN without light."""
    values = case.comparison.percentile(q)
    return float(np.nanmax(values)) if np.any(np.isfinite(values)) else float("nan")


def error_figure(result, output_dir: Path) -> Figure:
    """Median and 95th percentile (worst band) against sun zenith, one column per atmosphere,
    one line per solver, the Monte Carlo noise dashed."""
    atmospheres = list(result.plan.atmospheres)
    figure, axes = new_figure(2, len(atmospheres), width_in=4.2, height_in=3.4)
    for column, atmosphere in enumerate(atmospheres):
        for name in result.plan.solvers:
            rows = [c for c in result.cases if c.solver == name and c.atmosphere == atmosphere
                    and c.comparison is not None]
            for row, q in enumerate((50.0, 95.0)):
                axes[row][column].plot([c.sun_zenith_deg for c in rows],
                                       [100 * _worst_band(c, q) for c in rows], "o-", ms=3,
                                       label=name)
        noise = sorted({(c.sun_zenith_deg, float(np.nanmax(c.comparison.noise)))
                        for c in result.cases if c.atmosphere == atmosphere
                        and c.comparison is not None})
        for row, q in enumerate((50.0, 95.0)):
            axis = axes[row][column]
            if noise:
                axis.plot(*zip(*[(z, 100 * n) for z, n in noise], strict=True), "k--", lw=1,
                          label="Monte Carlo noise")
            axis.set_yscale("log")
            axis.axvline(90.0, color="0.6", lw=0.8)
            axis.set_xlabel("sun zenith angle [deg]")
            axis.set_ylabel(f"{'median' if q == 50 else '95th pct'} |L / L_MC - 1| [%]")
            axis.set_title(f"{atmosphere}", fontsize=9)
            axis.grid(alpha=0.3, which="both")
    axes[0][-1].legend(fontsize=7)
    name = save_figure(figure, output_dir, "compare_errors.png")
    return Figure(name, "Relative radiance error against the Monte Carlo reference over the "
                        "view grid, worst wavelength band (top: median, bottom: 95th "
                        "percentile); the dashed line is the reference's own noise (median "
                        "relative standard error, worst band); the sun is below the horizon "
                        "right of the grey line; missing points: outside the solver's domain.")


def fisheye_figure(result, spec: str, atmosphere: Atmosphere, solvers: dict, output_dir: Path,
                   ) -> Figure:
    """The fisheye sky of each solver of `atmosphere` (those that answered) at the plan's
    frame sun, all exposed as the first one's, over the false colour of log2(Y / Y_first)."""
    plan = result.plan
    camera = FisheyeCamera(plan.fisheye_size)
    sun = local_frame_directions(np.radians(plan.frame_sun_zenith_deg), np.radians(180.0))
    images = {}
    for name, solver in solvers.items():
        viewpoint = ground_viewpoint(0.0, solver.profile.bottom_radius_m)
        images[name] = render_sky(solver, camera, viewpoint, sun, atmosphere.planet.star,
                                  sun_disk=False)
    names = list(images)
    first = images[names[0]]
    xyz = {n: spectral_to_xyz(images[n].spectral, images[n].wavelengths_nm) for n in names}
    ev100 = metered_ev100(first, xyz[names[0]])
    figure, axes = new_figure(2, len(names), width_in=2.2, height_in=2.3)
    for k, n in enumerate(names):
        rgb = display_rgb8(xyz_to_rgb(xyz[n]), images[n].valid, ev100, 0.0, "aces")
        axes[0][k].imshow(rgb)
        axes[0][k].set_title(n, fontsize=9)
        for row in (0, 1):
            axes[row][k].set_axis_off()
        if k == 0:
            continue  # below the reference: the colour scale
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.log2(xyz[n][..., 1] / xyz[names[0]][..., 1])
        shown = axes[1][k].imshow(np.where(images[n].valid, ratio, np.nan), cmap="RdBu_r",
                                  vmin=-LOG2_RANGE, vmax=LOG2_RANGE)
        axes[1][k].set_title(f"log2(Y / Y_{names[0]})", fontsize=8)
    if len(names) > 1:
        scale = axes[1][0].inset_axes([0.1, 0.45, 0.8, 0.08])
        figure.colorbar(shown, cax=scale, orientation="horizontal",
                        label=f"log2(Y / Y_{names[0]}): -1 half, +1 double")
    index = plan.atmospheres.index(spec)
    name = save_figure(figure, output_dir, f"compare_fisheye_{index}.png")
    return Figure(name, f"{spec}, sun {plan.frame_sun_zenith_deg:g} deg from the zenith (south "
                        f"at the bottom), {plan.fisheye_size} px fisheyes from the ground, all "
                        f"exposed as {names[0]}'s; below: log2 of each luminance over "
                        f"{names[0]}'s (red: brighter, blue: darker; a Monte Carlo render "
                        "would take hours: the errors against it are in the tables).")
