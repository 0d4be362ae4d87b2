"""Precomputed atmosphere tables with multiple scattering (Bruneton & Neyret 2008; Bruneton 2017).

What is computed, for every wavelength of an `OpticalProfile` (docs/physics/tables.md):

- transmittance T(r, mu) to the top of the atmosphere, (n_r_t, n_mu_t, n_wl);
- single scattering per scattering constituent s WITHOUT its phase function,
  S_s(r, mu, mu_s, nu) = E_sun beta_s,s int_0^d T(x, p) n_s(p) T_sun(p) V(p) dt
  [W m^-2 nm^-1], so that the renderer applies p_s(nu) at lookup (sampled every 0.044 deg)
  and aerosol forward peaks stay sharp; and the sum of the orders n >= 2,
  M(r, mu, mu_s, nu) [W m^-2 sr^-1 nm^-1], phase functions included, except the peak
  corrections D_c of the n_c constituents whose forward peaks are clipped (below), tables of
  their own without phase function, which the renderer weights by the clipped phase function
  p*_c(nu) as it weights S_s by p_s(nu); interleaved as `scattering`
  (n_r, n_mu, n_mu_s, n_nu, n_s + n_c + 1, n_wl) = (S_1 .. S_n_s, D_1 .. D_n_c, M) (the
  tables of one cell adjacent, for fast lookups; `single_scattering` and
  `multiple_scattering` give S and M as views, `lookup_phase` the phase function of each
  table before M);
- indirect irradiance of horizontal ground, E(r, mu_s) = sum_{k=1}^{N-1} Delta E_k, the sky
  light of orders 1 .. N-1 (N = orders), (n_r_e, n_mu_s_e, n_wl) [W m^-2 nm^-1].

The orders are iterated as in Bruneton & Neyret (2008), Algorithm 4.1, and Bruneton 2017
(`model.cc::Precompute`); for n = 2 .. N:
  J_n(x, v)   = sum_s n_s(x) beta_s,s int_{4 pi} p_s(v . w) L_{n-1}(x, w) dw, where L_{n-1} is
                the radiance of order n-1 (Delta S_{n-1}; for n = 2 the single scattering with
                its phase functions) plus, for directions w that hit the ground, the ground lit
                by Delta E_{n-2} (Delta E_0 = direct sunlight) seen through the atmosphere;
  Delta E_{n-1}(x) = int_{mu > 0} L_{n-1}(x, w) mu dw;
  Delta S_n(x, v) = int_0^d T(x, p) J_n(p, v) dt;   M += Delta S_n;   E += Delta E_{n-1}.
Forward-peaked particles (aerosols, dust, cloud droplets): the orders >= 2 are computed in the
delta-M scaled medium of `phase_truncation` (each particle's forward peak clipped inside
`TableResolution.truncation_angle_deg` and counted as unscattered light), whose smooth phase
functions the sphere quadrature resolves; the first order stays exact (full phase functions,
true extinction). What the scaled medium's first order has more than the exact one's smooth part
(light scattered in the peak and then once more) is added: D_s = S*_s - (1 - f_s) S_s, times
p*_s(nu) (the TMS correction of Nakajima & Tanaka 1988, in table form), into M for the
constituents that are not clipped, as tables of their own for the clipped ones, whose p* is
flat inside the truncation angle and falls with the particles' wing beyond it: a kink that
the table's view-sun slices would interpolate linearly (+7 % 20 deg from a low sun with
Mars dust at 16 slices, docs/physics/tables.md), applied exactly per ray instead. The light
the peaks keep near the sun's direction is added to E as the scaled medium's direct sun less
the true one. The scaled medium's sun is corrected for what the peaks do to a low sun's beam
(`beam_spread`: deflected a few degrees, its light goes through much more or much less air),
and M, once all orders are in, for the same along the lines of sight (`sight_spread`: near
the horizon a peak event brings the light of a lower or higher view). Optically thick media
need many orders: once the ratio of successive orders settles, the orders beyond are a
geometric series, added at once (`TAIL_TOLERANCE`); where it settles slowly (cloud decks), the
limit of the orders is extrapolated from the last six by reduced-rank extrapolation
(`order_extrapolation`).
`AtmosphereTables.tail_share` says how much of M either tail is.
Paths whose last event is a ground reflection are not in the tables; the renderer adds the ground
with albedo / pi (direct sun + E) (Bruneton 2017). The ground albedo of the profile enters the
orders >= 2 through J.

Departures from Bruneton 2017, deliberate:
- J_n is stored as the source function S = J_n / beta_s (beta_s = sum_s n_s beta_s, the
  scattering coefficient; S is the phase-weighted mean incoming radiance, smooth in altitude)
  on (r, mu_s) nodes of the scattering table times a regular grid of outgoing directions
  relative to the sun's vertical plane, and multiplied by the exact beta_s along each ray
  (no interpolation of exponential densities between r nodes; against a table per
  constituent, 95 % of the orders >= 2 agree within 0.17 %). The sphere integral is a matrix
  product with phase matrices normalised so that each row integrates to exactly 1 (energy is
  conserved by the discrete sphere integral even where the quadrature does not resolve a
  forward peak; `phase_quadrature`, which takes a gas's matrix in rank 5);
- transmittances along table rays come from a wavelength-free table of column densities in the
  transmittance parameterisation (towards the sun: the transmittance table, as Bruneton); rays
  are sampled densest at their lowest point and at the observer.
Wavelengths are processed in batches (`wavelength_batch`), so working memory does not grow with
the number of wavelengths beyond the result tables.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, fields, replace
from typing import NamedTuple

import numpy as np

from skyscatter.atmosphere.model import DEFAULT_SCATTERING_ORDERS, OpticalProfile
from skyscatter.blas_threads import idle_threads_sleep
from skyscatter.errors import InputError
from skyscatter.transport import _kernels, _table_build_kernels
from skyscatter.transport._table_common_kernels import flat_tables
from skyscatter.transport.aureole import PeakAureole, peak_aureole
from skyscatter.transport.beam_spread import BeamSpread, beam_spread
from skyscatter.transport.order_extrapolation import OrderExtrapolation
from skyscatter.transport.phase_quadrature import (
    PhaseQuadrature,
    phase_quadrature,
    source_function,
    sphere_grids,
)
from skyscatter.transport.phase_truncation import truncate_forward_peak
from skyscatter.transport.scatterers import sample_phase_functions, scattering_constituents
from skyscatter.transport.sight_spread import sight_spread_source, view_zenith_angles
from skyscatter.transport.table_parameterisation import (
    COS_SUN_ZENITH_MIN,
    irradiance_r_mu_s_from_x,
    scattering_r_from_u,
    transmittance_r_mu_from_x,
)

__all__ = [
    "AtmosphereTables",
    "TableResolution",
    "precompute_tables",
    "radius_warp",
    "sample_phase_functions",
    "scattering_constituents",
    "thick_layer_resolution",
]

# Direct sun on the ground for the ground term of the second order: mu_s samples over [-1, 1].
DIRECT_GROUND_SAMPLES = 1025
# Forward peaks of particles clipped inside this angle for the orders >= 2 (`phase_truncation`):
# measured against the Monte Carlo reference, benchmarks/bench_forward_peak.py.
TRUNCATION_ANGLE_DEG = 15.0
MAX_TRUNCATION_ANGLE_DEG = 90.0
# A lobe that loses less than this share of its light to the clip is left alone: the orders >= 2's
# quadrature holds it, and the clip would cost the scaled medium's first-order pass and the
# aureole's lookups. Earth's aerosol (Henyey-Greenstein g 0.65, 3.7 % above 15 deg) against the
# Monte Carlo with and without the clip: the same to 0.03 points of median error, 0.1 of the
# 95th percentile, at sun zenith 0-85 deg (benchmarks/bench_forward_peak.py, docs/validation.md).
TABLE_MIN_PEAK_FRACTION = 0.05
# The orders beyond the last one computed follow a geometric series once the ratio of successive
# orders has settled (the leading eigenvalue of the scattering operator takes over, as in the
# successive-orders method: Lenoble 1985, "Radiative Transfer in Scattering and Absorbing
# Atmospheres", ch. 3): from order TAIL_MIN_ORDER on, when the ratio r changed by at most
# RATIO_SETTLED from one order to the next, the iteration stops as soon as the tail's
# uncertainty, its share of the orders >= 2 times the relative change of r/(1 - r) that the
# last change of r makes, is below TAIL_TOLERANCE; at the last order allowed the tail is added
# anyway, in each wavelength whose r has settled (wavelengths computed together do not change
# each other's tables). Before it does, from order
# `order_extrapolation.EXTRAPOLATION_FIRST_ORDER` on, the orders' limit may be extrapolated by
# RRE (`order_extrapolation`): a stratus deck of optical depth 20 (ratio 0.953) stops at 16
# orders instead of the 30 this rule needs
# (benchmarks/bench_precompute_media.py, docs/physics/tables.md).
TAIL_MIN_ORDER = 4
# ... and only once the series is at most this share of the orders >= 2: beyond it the last
# order's shape is not the tail's (fog stopped with a 32 % tail was +5.6 % from DISORT at
# 550 nm, with the orders iterated on +4.2 %); Earth and Mars stop with 1.5-3.6 %
TAIL_SHARE_MAX = 0.1
# The orders from COARSE_FROM_ORDER on, diffuse light smooth in the view angle and the
# azimuth, are iterated on a grid with half the view-zenith cells and COARSE_NU_SLICES
# view-sun slices (azimuths 0, 60, 120, 180 deg; `_coarse_grid`: their ray integrals, most of
# an order's cost, take a quarter of the time), summed there and added to the tables
# interpolated back (`_OrderSums`). The dusty Mars presets stop before it (at 6);
# `earth-overcast` against DISORT, median at 550 nm: -1.0 % on the full grid, -1.1 % with mu
# halved, -1.0 % with mu halved and 4 slices, +3.4 % with mu_s halved instead (the sun's
# elevation needs its cells in every order; docs/physics/tables.md).
COARSE_FROM_ORDER = 7
# ... and from CLEAR_COARSE_FROM_ORDER on in clear air (`is_clear`: no optically thick layer,
# no optically significant forward-scattering particles), whose orders >= 4 are smooth already:
# `earth` (16 bands; from the ground and 5 km, sun zenith 0-94 deg, views 0-85 deg) changes by
# 0.003-0.021 % (median per case), 0.13 % (99th percentile), 0.74 % at most (the twilight
# horizon) against the orders on the full grid; from the 3rd order 0.04 % (median), 0.66 %
# (99th percentile). `mars-physical` (16 slices for its dust) would lose its orders' aureole
# on 4 slices: from the 4th order 1.3 % (99th percentile), 5.7 % at most. Only where the
# view-zenith axis has at least CLEAR_COARSE_MIN_MU cells: the limb seen from space needs them
# (`earth` from 400 km, views 0.2-1.4 deg above the horizon, against the Monte Carlo: 95th
# percentile 11.2 -> 12.0 % with 128 cells, but 59 -> 68 % with the viewer's preview's 64).
CLEAR_COARSE_FROM_ORDER = 4
CLEAR_COARSE_MIN_MU = 128
COARSE_NU_SLICES = 4
# ... and on a sphere of COARSE_SPHERE_THETA x COARSE_SPHERE_PHI incoming directions (48 x 24 on
# the full grid): the sphere integral's matrix products and the incoming radiance's gather
# scale with it. `earth-overcast` 81.6 -> 70.7 s CPU, `earth` 18.7 -> 15.9 s in one run
# (benchmarks/bench_precompute_media.py); against DISORT the ground's signed
# median (4 bands) moves +0.21 / +0.04 / -0.16 -> +0.22 / +0.01 / -0.22 % (sun 0 / 30 / 60 deg),
# inside the deck by at most 0.06 % (benchmarks/compare_disort_inside.py); 24 x 12 is no faster.
COARSE_SPHERE_THETA = 32
COARSE_SPHERE_PHI = 16
# Wavelengths computed together by default: the ray integrals' wavelength-independent part (a
# third of Earth's time at 16 wavelengths) is paid once a batch; the working memory is ~8 MiB a
# wavelength besides the tables' 15 (48 wavelengths, 4 orders: CPU 30.8 s in batches of 16,
# 22.7 s in one, +968 against +1139 MiB; docs/performance.md)
WAVELENGTH_BATCH = 48
# An order's source function is built this many r nodes at a time, each batch of nodes from
# its own incoming radiance (Earth: 11 instead of 90 MiB, and faster), where OpenBLAS's idle
# threads sleep at once after each node batch's matrix product (`blas_threads`); else all
# nodes at once (their spin took 12-25 % more time in batches; docs/performance.md)
SOURCE_NODE_CHUNK = 4
# Orders that grow by this factor twice in a row are refused (`_check_converging`).
DIVERGING_RATIO = 1.0
RATIO_SETTLED = 0.02
TAIL_TOLERANCE = 1e-3


# The radius axis of the scattering table (`radius_warp`): segments of its piecewise-linear
# warp, uniform in rho / H. Where a cell of Bruneton's axis (REFERENCE_RADIUS_CELLS uniform in
# rho / H) would hold more than THICK_OPTICAL_DEPTH, the optically thick layers get a share of
# the cells, up to THICK_CELL_SHARE, in proportion to their optical depth, and the column table
# gets at least THICK_LAYER_QUADRATURE (`thick_layer_resolution`); the table rays refine
# themselves inside such layers (`_table_build_kernels._refined_distances`). Measured on
# `earth-overcast` (a deck of optical depth 20, 500 m thick) against DISORT at 550 nm with the
# sun 60 deg up, median of tables / DISORT - 1: Bruneton's axis with 32 / 64 / 128 radius cells
# +53 / -38 / +7 % (the answer jumps with where the 1-4 cells inside the deck fall); the warp
# +19 % (32 cells) and +43 % (64): the column table's 64 radii (2 in the deck) then decide it.
# With the rays refined, their columns integrated along them and the sun's optical depth
# interpolated between the column table's rows, sun 30 deg from the zenith: 512 / 1024 / 2048
# radii -3.2 / -1.9 / -1.5 % (docs/physics/tables.md). Inside a layer the cells crowd at its
# edges, where the light changes within about one optical depth (the diffusion regime inside
# varies slowly): the cells' density in optical depth falls as 1 / (1 + d / EDGE_OPTICAL_DEPTH),
# d the optical distance to the nearer end of the column. The stratus at 550 nm, sun 30 deg
# from the zenith, median / 95th percentile of |tables / DISORT - 1|: 1.77 / 7.0 % with the
# cells uniform in optical depth (64 segments), 2.20 / 3.9 % (512), crowded at the edges with
# 128 / 256 / 512 segments 1.23 / 1.7, 0.37 / 0.74, 0.62 / 1.0 %; EDGE_OPTICAL_DEPTH 0.5 / 2
# (512 segments) 1.09 / 1.7, 1.72 / 2.2 %. The deck spans 7-8 of the 256 segments.
RADIUS_WARP_SEGMENTS = 256
EDGE_OPTICAL_DEPTH = 1.0
# the fine grid of rho / H on which the warp's optical depths are integrated
RADIUS_WARP_FINE = 16384
REFERENCE_RADIUS_CELLS = 32
THICK_OPTICAL_DEPTH = 1.0
THICK_CELL_SHARE = 0.5
THICK_LAYER_QUADRATURE = {"transmittance_r": 1024}
# Below an optically thick layer the light changes with exp(-tau / mu_s) across the daytime sun
# zenith angles, where Bruneton's mu_s axis has its last three of 40 cells at 47.9, 36.2 and
# 0 deg: `earth-fog` at 550 nm against DISORT (sun 30 deg from the zenith) -13 % towards the
# sun and +13 % away from it, already at one order. Tables with such a layer spend
# THICK_SUN_ANGLE_SHARE of the mu_s axis uniformly in the chord of the sun's zenith angle
# (`sun_angle_share`; with 40 cells, 11 within 50 deg of the zenith, 5 deg apart there, and
# 1.3 deg instead of 0.8 deg at the horizon). So do tables with optically significant
# forward-scattering particles (`has_forward_particles`, below): their orders >= 2 change with
# the sun's zenith angle faster than linearly across Bruneton's cell of 0-36 deg; `exo-hazy`
# (haze of optical depth 1) at 566 nm against the Monte Carlo, the zenith with the sun 24 deg
# from it, 1.150 -> 1.020, 30 deg from the zenith on the far side 1.226 -> 1.009.
THICK_SUN_ANGLE_SHARE = 0.5
# Where a cell of Bruneton's radius axis holds more than this optical depth, the source function
# is interpolated in radius by a cubic, not linearly (`cubic_source`): across such cells it
# curves, and the linear interpolation loses light at every order (the tau = 8 slab of van de
# Hulst, 0.49 per cell, R + T = 0.961 instead of 1). Earth (0.05), `mars-physical` (0.04) and
# `exo-hazy` (0.17) keep the linear interpolation; the dust storm (0.43), the fog and the
# stratus take the cubic. Measured in docs/physics/tables.md, "Thick layers".
CUBIC_SOURCE_OPTICAL_DEPTH = 0.25

# Forward-scattering particles of some optical depth give the orders >= 2 an azimuthal
# structure that 8 view-sun slices (25.7 deg apart) interpolate away: where the particles whose
# phase function has an asymmetry parameter of at least FORWARD_ASYMMETRY hold a vertical
# scattering optical depth of at least FORWARD_OPTICAL_DEPTH (at any wavelength), and no layer
# is optically thick, the tables get at least FORWARD_NU_SLICES slices
# (`forward_scattering_resolution`). Against the Monte Carlo (benchmarks/bench_forward_peak.py,
# 8 bands, median / 95th percentile / aureole): `mars-hg-dust` (HG g 0.65, optical depth 0.5)
# with the sun 85 deg from the zenith 2.19 / 5.8 / 4.1 % with 8 slices, 1.58 / 3.7 / 2.6 % with
# 16; `mars-physical` at 60 deg 1.07 / 4.1 / 4.6 -> 0.68 / 2.7 / 2.5 %; `mars-dust-storm` at
# 30 deg aureole 20.7 -> 5.9 %. Earth's aerosol (optical depth 0.1) stays at 8; so does an
# optically thick layer above the ground (a cloud deck): below it the light has lost its
# forward structure to many scatterings, and 16 slices would take the stratus's tables from
# 2.9 to ~5 x Earth's CPU time (issue 17 allows 3). A thick layer at the ground (fog: its
# extinction at the ground at least GROUND_LAYER_SHARE of its largest) gets 16: the ground's
# observers look out from inside it, where the orders >= 2 keep an aureole. `earth-fog` against
# DISORT at 550 nm (benchmarks/compare_disort.py nodes, median / 95th percentile): sun 30 deg
# from the zenith 1.20 / 2.4 -> 0.63 / 1.9 %, 60 deg 2.04 / 3.8 -> 1.05 / 2.8 %, 0 deg 0.59 /
# 2.0 % either way; its CPU time 82 -> 129 s.
FORWARD_ASYMMETRY = 0.5
FORWARD_OPTICAL_DEPTH = 0.3
FORWARD_NU_SLICES = 16
GROUND_LAYER_SHARE = 0.5


@dataclass(frozen=True)
class TableResolution:
    """Table sizes and quadrature counts of the precomputation.

    Table sizes default to Bruneton 2017 (atmosphere/constants.h): transmittance 256 (mu) x 64
    (r); scattering r 32, mu 128 (two halves of 64), mu_s 40 (Bruneton: 32 down to sun zenith
    102 deg; ours reach 120 deg, and 40 cells keep the daytime cells where 32 had them:
    docs/physics/tables.md, "Twilight"), nu 8; irradiance 64 (mu_s) x 16 (r). Quadrature:
    transmittance_samples  column integral per transmittance entry (Bruneton: 500 intervals)
    ray_samples            samples along each scattering-table ray for single scattering
                           (Bruneton: 50 uniform; ours crowd near the lowest point)
    multiple_ray_samples   the same for the orders >= 2, whose integrand is smoother
    sphere_theta, sphere_phi
                           incoming directions of the scattering density: polar midpoints over
                           [0, pi] and azimuth midpoints over [0, pi], mirrored (Bruneton: 16 x
                           32 over the whole sphere; 48 x 24 halves the largest error of the
                           second order against a brute-force integral, 3.1 % -> 2.1 %;
                           the coarse orders take at most 32 x 16: `coarse_resolution`)
    density_theta, density_phi
                           outgoing directions where J is tabulated: regular over [0, pi]
                           including both ends
    irradiance_theta, irradiance_phi
                           hemisphere quadrature of the indirect irradiance: polar midpoints in
                           [0, pi/2], azimuth midpoints in [0, pi] mirrored (Bruneton: 16 x 64)
    phase_angles           samples of each phase function over [0, pi] for the kernels
    truncation_angle_deg   the orders >= 2 see particle phase functions with their forward
                           peak clipped inside this angle, delta-M scaled
                           (`phase_truncation`); 0: no truncation
    """

    transmittance_r: int = 64
    transmittance_mu: int = 256
    scattering_r: int = 32
    scattering_mu: int = 128
    scattering_mu_s: int = 40
    scattering_nu: int = 8
    irradiance_r: int = 16
    irradiance_mu_s: int = 64
    transmittance_samples: int = 500
    ray_samples: int = 64
    multiple_ray_samples: int = 32
    sphere_theta: int = 48
    sphere_phi: int = 24
    density_theta: int = 33
    density_phi: int = 13
    irradiance_theta: int = 16
    irradiance_phi: int = 32
    phase_angles: int = 4097
    truncation_angle_deg: float = TRUNCATION_ANGLE_DEG

    def __post_init__(self) -> None:
        if not 0.0 <= self.truncation_angle_deg <= MAX_TRUNCATION_ANGLE_DEG:
            raise InputError(f"TableResolution.truncation_angle_deg = "
                             f"{self.truncation_angle_deg!r} must lie in [0, "
                             f"{MAX_TRUNCATION_ANGLE_DEG:g}] deg", key="truncation_angle_deg",
                             value=self.truncation_angle_deg,
                             allowed=f"[0, {MAX_TRUNCATION_ANGLE_DEG:g}]")
        for field in fields(self):
            if field.name == "truncation_angle_deg":
                continue
            value = getattr(self, field.name)
            if not isinstance(value, int | np.integer) or value < 2:
                raise InputError(f"TableResolution.{field.name} = {value!r} must be an integer "
                                 ">= 2", key=field.name, value=value, allowed="integer >= 2")
        if self.scattering_mu % 2 or self.scattering_mu < 4:
            raise InputError(f"TableResolution.scattering_mu = {self.scattering_mu} must be even "
                             "and >= 4 (two halves: rays that hit the ground and rays that miss "
                             "it)", key="scattering_mu", value=self.scattering_mu,
                             allowed="even integer >= 4")

    def scaled(self, factor: float) -> TableResolution:
        """The table sizes multiplied by `factor` (the mu axis kept even); quadrature unchanged."""
        def size(n: int) -> int:
            return max(2, int(round(n * factor)))
        return replace(self, transmittance_r=size(self.transmittance_r),
                       transmittance_mu=size(self.transmittance_mu),
                       scattering_r=size(self.scattering_r),
                       scattering_mu=max(4, 2 * size(self.scattering_mu // 2)),
                       scattering_mu_s=size(self.scattering_mu_s),
                       scattering_nu=size(self.scattering_nu),
                       irradiance_r=size(self.irradiance_r),
                       irradiance_mu_s=size(self.irradiance_mu_s))


@dataclass(frozen=True, eq=False)
class AtmosphereTables:
    """Precomputed tables of one atmosphere (module docstring); arrays C order, wavelength last.

    transmittance  (n_r_t, n_mu_t, n_wl) float64: T to the top for rays that miss the ground [-]
    scattering     (n_r, n_mu, n_mu_s, n_nu, n_s + n_c + 1, n_wl) float32, interleaved:
                   [..., s, :] single scattering of constituent `scattering_names[s]` without
                   phase [W m^-2 nm^-1]; [..., n_s + c, :] the peak correction D_c of the c-th
                   clipped constituent without phase [W m^-2 nm^-1] (module docstring; n_c = 0
                   without clipped peaks or with one order); [..., -1, :] the orders >= 2 with
                   phases [W m^-2 sr^-1 nm^-1]
    irradiance     (n_r_e, n_mu_s_e, n_wl) float64: indirect irradiance on horizontal ground
                   from sky light of orders 1 .. orders-1 [W m^-2 nm^-1]
    phase          (n_s, n_angle, n_wl) float64: p_s at scattering angles uniform in [0, pi]
                   [sr^-1]
    peak_correction_phase  (n_c, n_angle, n_wl) float64: on the same angles, the clipped phase
                   function p*_c that weights the peak correction D_c [sr^-1]
    peak_correction_names  the constituents of the peak corrections D_1 .. D_n_c
    order_mean_radiance, order_zenith_radiance  (orders, n_wl): radiance of each order alone,
                   the mean over all table cells and the zenith seen from the ground with the
                   sun at the zenith [W m^-2 sr^-1 nm^-1]; they show how the orders converge
                   (rows beyond `orders_computed` are 0)
    orders_computed   the orders iterated (<= orders: the iteration stops once the orders
                   beyond are a geometric series below `TAIL_TOLERANCE`, or their limit is
                   extrapolated, `order_extrapolation`)
    tail_share     (n_wl,): the extrapolated rest (series or limit) over the orders >= 2
                   iterated (0 where none was added): how far from convergence it stopped
    peak_transmittance (n_r_t, n_mu_t, n_wl) float64: exp(-x), x the peak depth (the
                   scattering the truncated peaks take out, f beta_s) from (r, mu) to the top,
                   on the transmittance table's axes [-]
    aureole_shape  (n_x, n_psi, n_wl) float64: the angular shape of the light scattered twice
                   or more in the peaks (`transport.aureole.PeakAureole`) [sr^-1]
    aureole_blur   (n_x, n_psi, n_wl) float64: on the same nodes, the peaks' blur of light
                   scattered once in the smooth part (`transport.aureole.PeakAureole`) [sr^-1]
    aureole_limits (x_max, psi_max [rad]) of that table; psi_max = 0 where nothing is clipped
    radius_warp    (RADIUS_WARP_SEGMENTS + 1,) float64: the scattering table's radius axis
                   (`radius_warp`, `table_parameterisation.scattering_u_r`)
    sun_angle_share  the share of the mu_s axis uniform in sin(sun zenith / 2)
                   (`sun_angle_share`, `table_parameterisation.scattering_u_mu_s`)
    """

    wavelengths_nm: np.ndarray
    bottom_radius_m: float
    top_radius_m: float
    min_cos_sun_zenith: float
    resolution: TableResolution
    orders: int
    scattering_names: tuple[str, ...]
    scattering_constituents: tuple[int, ...]
    peak_correction_names: tuple[str, ...]
    transmittance: np.ndarray
    scattering: np.ndarray
    irradiance: np.ndarray
    phase: np.ndarray
    peak_correction_phase: np.ndarray
    order_mean_radiance: np.ndarray
    order_zenith_radiance: np.ndarray
    orders_computed: int
    tail_share: np.ndarray
    peak_transmittance: np.ndarray
    aureole_shape: np.ndarray
    aureole_blur: np.ndarray
    aureole_limits: np.ndarray
    radius_warp: np.ndarray
    sun_angle_share: float

    @property
    def single_scattering(self) -> np.ndarray:
        """(n_s, n_r, n_mu, n_mu_s, n_nu, n_wl) view: single scattering per constituent, no
        phase function."""
        return np.moveaxis(self.scattering[..., :len(self.scattering_constituents), :], -2, 0)

    @property
    def lookup_phase(self) -> np.ndarray:
        """(n_s + n_c, n_angle, n_wl): the phase function that weights each table before the
        orders >= 2 (`phase`, then `peak_correction_phase`) [sr^-1]."""
        return np.concatenate([self.phase, self.peak_correction_phase])

    @property
    def multiple_scattering(self) -> np.ndarray:
        """(n_r, n_mu, n_mu_s, n_nu, n_wl) view: orders >= 2, phase functions included."""
        return self.scattering[..., -1, :]

    @property
    def nbytes(self) -> int:
        return sum(a.nbytes for a in (self.transmittance, self.scattering, self.irradiance,
                                      self.phase, self.peak_correction_phase,
                                      self.peak_transmittance, self.aureole_shape,
                                      self.aureole_blur))


def precompute_tables(profile: OpticalProfile, resolution: TableResolution | None = None,
                      orders: int = DEFAULT_SCATTERING_ORDERS, *,
                      min_cos_sun_zenith: float = COS_SUN_ZENITH_MIN,
                      wavelength_batch: int = WAVELENGTH_BATCH,
                      progress: Callable[[int, int, str], None] | None = None,
                      on_order: Callable[[int, slice, np.ndarray, np.ndarray], None] | None = None
                      ) -> AtmosphereTables:
    """Precompute the tables of `profile` with `orders` scattering orders (module docstring).

    Parameters
    ----------
    profile : OpticalProfile
        The atmosphere sampled at its wavelengths.
    resolution : TableResolution, optional
        Table sizes and quadrature; Bruneton 2017's sizes by default.
    orders : int
        Number of scattering orders N >= 1 (1: single scattering only, as the ray-marching
        solver; 4 is Bruneton's default for Earth; dusty atmospheres need 10 or more).
    min_cos_sun_zenith : float
        mu_s_min, the smallest cos(sun zenith) tabulated (below it the sky of mu_s_min is
        used): -0.5 (sun zenith 120 deg) by default, which covers astronomical twilight on
        every planet (`table_parameterisation.COS_SUN_ZENITH_MIN`); Bruneton 2017 used
        cos(102 deg) = -0.208 for Earth.
    wavelength_batch : int
        Wavelengths computed together; bounds the working memory besides the result tables
        (about 8 MiB a wavelength at the default resolution; each batch more costs the
        wavelength-independent part of the ray integrals again, `WAVELENGTH_BATCH`).
    progress : callable(done, total, stage), optional
        Called after each step.
    on_order : callable(order, batch, multiple, irradiance), optional
        Called after each order n of each wavelength batch (a slice) with read-only views of
        the sum of orders 2 .. n (n_r, n_mu, n_mu_s, n_nu, n_wl) and of the sky light on the
        ground of orders 1 .. n - 1 (n_r_e, n_mu_s_e, n_wl) so far: the tables truncated at n
        orders, for convergence studies (benchmarks/bench_orders.py); the orders' table M,
        without the peak corrections that have tables of their own.

    Returns
    -------
    AtmosphereTables
    """
    resolution = resolution or TableResolution()
    if int(orders) != orders or orders < 1:
        raise InputError(f"orders = {orders!r} must be an integer >= 1", key="orders",
                         value=orders, allowed="integer >= 1")
    if not -1.0 <= min_cos_sun_zenith < 0.5:
        raise InputError(f"min_cos_sun_zenith = {min_cos_sun_zenith!r} must lie in [-1, 0.5)",
                         key="min_cos_sun_zenith", value=min_cos_sun_zenith,
                         allowed="[-1, 0.5)")
    if int(wavelength_batch) != wavelength_batch or wavelength_batch < 1:
        raise InputError(f"wavelength_batch = {wavelength_batch!r} must be an integer >= 1",
                         key="wavelength_batch", value=wavelength_batch, allowed=">= 1")
    orders = int(orders)
    warp = radius_warp(profile)
    bottom, top = float(profile.bottom_radius_m), float(profile.top_radius_m)
    mu_s_min = float(min_cos_sun_zenith)
    h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
    density = np.ascontiguousarray(profile.density, dtype=np.float64)
    wavelengths = profile.wavelengths_nm
    n_wl = wavelengths.size
    scatterers = scattering_constituents(profile)
    n_s = len(scatterers)
    scatterer_index = np.array(scatterers, dtype=np.int64)
    batches = [slice(i, min(i + int(wavelength_batch), n_wl))
               for i in range(0, n_wl, int(wavelength_batch))]
    res = forward_scattering_resolution(thick_layer_resolution(resolution, warp), profile,
                                        warp)
    total_steps = 1 + len(batches) * orders
    step = 0

    def report(stage: str) -> None:
        nonlocal step
        step += 1
        if progress is not None:
            progress(step, total_steps, stage)

    columns = _kernels.column_table(res.transmittance_r, res.transmittance_mu,
                                    res.transmittance_samples, bottom, top, h_step, density)
    depth = np.einsum("cw,crm->rmw", profile.extinction_per_density, columns)
    transmittance = np.exp(-depth)
    # the first order's sun: optical depths inside optically thick layers, else transmittances
    # (`single_scattering_table`)
    thick = not is_identity_warp(warp)
    report("transmittance")
    phase = sample_phase_functions(profile, scatterers, res.phase_angles)
    smooth_phase, peak = truncate_forward_peak(phase, res.truncation_angle_deg,
                                               min_fraction=TABLE_MIN_PEAK_FRACTION)
    truncated = bool(np.any(peak > 0.0))
    # the orders >= 2 see the delta-M scaled medium (`phase_truncation`); without a clipped
    # peak it is the medium itself
    scaled = _scaled_optics(profile, scatterer_index, peak)
    sun_table = depth if thick else transmittance
    peak_phase = _mixed_peak(profile, scaled, scatterer_index, phase, smooth_phase, peak)
    gains = None
    if truncated:  # the scaled medium's first order lights the second (below)
        # its sun: the scaled beam, corrected for the peaks' spread of a low sun's light
        # (where the solver resolves the particles: not in a cloud deck, fog or a dust storm)
        gains = _beam_gains(beam_spread(profile, scaled.removed, peak_phase,
                                        res.truncation_angle_deg), res, bottom, top)
        scaled_depth = np.einsum("cw,crm->rmw", scaled.extinction, columns)
        if gains is not None:
            scaled_depth -= np.log(gains.transmittance)
        scaled_sun_table = scaled_depth if thick else np.exp(-scaled_depth)
    peak_transmittance, aureole = _peak_aureole(profile, scaled, scatterer_index, peak_phase,
                                                smooth_phase, peak, columns,
                                                res.truncation_angle_deg)
    node_altitude = np.array([scattering_r_from_u((k + 0.5) / res.scattering_r, bottom, top,
                                                  res.scattering_r, warp)
                              for k in range(res.scattering_r)]) - bottom
    # linear between levels, 0 above the top: as `_kernels.density_at`
    node_density = np.array([np.interp(node_altitude, profile.altitudes_m, profile.density[c],
                                       right=0.0)
                             for c in scatterers]).reshape(n_s, res.scattering_r)
    # scattering per density of every constituent (absorbers: 0), for beta_s along rays
    scattering_all = np.where(np.isin(np.arange(len(profile.names)), scatterers)[:, None],
                              scaled.scattering, 0.0)
    # the peak corrections of the clipped constituents get tables of their own (module
    # docstring): slot[s] their index among the tables after the single scattering, else -1
    clipped = np.flatnonzero(np.any(peak > 0.0, axis=1) & (orders > 1))
    slot = np.full(n_s, -1, dtype=np.int64)
    slot[clipped] = np.arange(clipped.size)
    multiple_slot = n_s + clipped.size
    scattering = np.zeros((res.scattering_r, res.scattering_mu, res.scattering_mu_s,
                           res.scattering_nu, multiple_slot + 1, n_wl), dtype=np.float32)
    irradiance = np.zeros((res.irradiance_r, res.irradiance_mu_s, n_wl))
    order_mean = np.zeros((orders, n_wl))
    order_zenith = np.zeros((orders, n_wl))
    tail_share = np.zeros(n_wl)
    orders_computed = 1
    grid = _table_build_kernels.TableGrid(
        n_r=res.scattering_r, n_mu=res.scattering_mu, n_mu_s=res.scattering_mu_s,
        n_nu=res.scattering_nu, bottom_radius=bottom, top_radius=top, mu_s_min=mu_s_min,
        sun_angle_share=sun_angle_share(profile, warp), radius_warp=warp,
        cubic_source=cubic_source(profile))

    coarse_from = (CLEAR_COARSE_FROM_ORDER if is_clear(profile, warp)
                   and res.scattering_mu >= CLEAR_COARSE_MIN_MU else COARSE_FROM_ORDER)
    sun_radius = float(profile.sun_angular_radius_rad)
    node_chunk = SOURCE_NODE_CHUNK if idle_threads_sleep() else res.scattering_r
    cumulative = _kernels.cumulative_columns(density, h_step)
    for batch in batches:
        medium = _table_build_kernels.RayMedium(
            h_step=h_step, density=density, columns=columns,
            extinction=np.ascontiguousarray(profile.extinction_per_density[:, batch]),
            cumulative=cumulative)
        scaled_medium = medium._replace(
            extinction=np.ascontiguousarray(scaled.extinction[:, batch]))
        sun = np.ascontiguousarray(profile.toa_irradiance[batch], dtype=np.float64)
        albedo = np.ascontiguousarray(profile.ground_albedo[batch], dtype=np.float64)
        phase_b = np.ascontiguousarray(phase[:, :, batch])
        smooth_b = np.ascontiguousarray(smooth_phase[:, :, batch])
        beta_s = profile.scattering_per_density[scatterer_index][:, batch]  # (n_s, n_b)
        n_b = batch.stop - batch.start
        label = f"wavelengths {batch.start + 1}-{batch.stop} of {n_wl}"

        # the exact first order written into the tables' own slots (no copy beside them), and
        # the scaled medium's, which lights the second order; the tables keep the exact first
        # order and gain what the scaled one has more (TMS, module docstring)
        single = scattering[..., :n_s, batch]
        scaled_pass = truncated and orders > 1
        peak_b = np.ascontiguousarray(peak[:, batch])
        scaled_single = np.empty(single.shape if scaled_pass else (0,) * single.ndim,
                                 dtype=np.float32)
        first_orders = _FirstOrders(
            np.ascontiguousarray(sun_table[..., batch]),
            np.ascontiguousarray(sun[None, :] * beta_s),
            np.ascontiguousarray((scaled_sun_table if truncated else sun_table)[..., batch]),
            np.ascontiguousarray(sun[None, :] * (1.0 - peak_b) * beta_s))
        first_orders.compute(grid, medium, scaled_medium, res.ray_samples, thick,
                             scatterer_index, sun_radius, single, scaled_single)
        if scaled_pass:
            _table_build_kernels.peak_differences(
                scaled_single, single, 1.0 - peak_b, smooth_b, slot, grid,
                scattering[..., n_s:, batch])
            # the light the peak scatters stays near the sun: on the ground it is the direct
            # sun of the scaled medium less the true one
            scaled_direct = _table_build_kernels.direct_irradiance_nodes(
                res.irradiance_r, res.irradiance_mu_s, grid, scaled_medium, sun, sun_radius)
            if gains is not None:
                scaled_direct *= gains.irradiance[..., batch]
            irradiance[..., batch] = scaled_direct - _table_build_kernels.direct_irradiance_nodes(
                res.irradiance_r, res.irradiance_mu_s, grid, medium, sun, sun_radius)
        else:
            scaled_single = single
        order_mean[0, batch], order_zenith[0, batch] = _table_build_kernels.order_statistics(
            single, True, phase_b, grid)
        report(f"single scattering, {label}")
        if on_order is not None:
            on_order(1, batch, _read_only(scattering[..., multiple_slot, :]),
                     _read_only(irradiance))
        if orders == 1 or n_s == 0:  # nothing scatters: no higher orders
            continue
        phases, theta_in, phi_in = _sphere_integral(smooth_b, res)
        scaled_beta_s = scaled.scattering[scatterer_index][:, batch]
        previous, previous_phase = ((scaled_single, smooth_b) if scaled_pass else
                                    _single_in_place(scattering[..., batch], single, smooth_b))
        use_phase, delta = True, None
        del scaled_single  # `previous` holds it until the second order has read it
        extrapolation = OrderExtrapolation()
        ground = _table_build_kernels.direct_ground_irradiance(
            DIRECT_GROUND_SAMPLES, grid, scaled_medium, sun, sun_radius)
        if gains is not None:
            ground *= gains.ground[:, batch]
        order_res, order_grid = res, grid
        sums = _OrderSums(scattering[..., multiple_slot, batch])
        to_full = np.ones((2, n_b))  # the statistics' scale of the order grid's to the full's
        for order in range(2, orders + 1):
            if order == coarse_from and (coarse := _coarse_grid(res, grid)) is not None:
                order_res, order_grid, restrict, prolong = coarse
                previous = _resampled(previous[..., 0, :], restrict)[..., None, :]
                phases, theta_in, phi_in = _sphere_integral(smooth_b, order_res)
                delta = None  # the last order on the full grid: its memory goes now
                sums.coarsen(restrict, prolong)
                # the last order's statistics on both grids: the series' ratios and the
                # tail's share compare like with like
                on_coarse = np.array(_table_build_kernels.order_statistics(
                    previous, use_phase, previous_phase, order_grid))
                full = np.array([order_mean[order - 2, batch], order_zenith[order - 2, batch]])
                to_full = np.divide(full, on_coarse, out=np.ones_like(full),
                                    where=on_coarse > 0.0)
            lit = _table_build_kernels.LitOrder(tables=flat_tables(previous),
                                                n_t=previous.shape[4], use_phase=use_phase,
                                                phase_table=previous_phase)
            # the source a few r nodes at a time: the incoming radiance of all nodes at once
            # was a third of the working memory
            source = np.empty((order_res.scattering_r, order_res.density_theta,
                               order_res.scattering_mu_s * order_res.density_phi * n_b),
                              dtype=np.float32)
            for first in range(0, order_res.scattering_r, node_chunk):
                nodes = slice(first, min(first + node_chunk, order_res.scattering_r))
                incoming = _table_build_kernels.incoming_radiance(
                    order_grid, scaled_medium, theta_in, phi_in, lit, ground, albedo,
                    (nodes.start, nodes.stop))
                source[nodes] = source_function(phases, incoming, scaled_beta_s,
                                                node_density[:, nodes], order_res)
                del incoming
            delta_irradiance = _table_build_kernels.indirect_irradiance(
                res.irradiance_r, res.irradiance_mu_s, res.irradiance_theta,
                res.irradiance_phi, order_grid, lit)
            irradiance[..., batch] += delta_irradiance
            ground = np.ascontiguousarray(delta_irradiance[0])
            del lit, previous, delta  # read: their memory goes to the next order
            delta = _table_build_kernels.multiple_scattering_table(
                order_grid, scaled_medium, res.multiple_ray_samples,
                np.ascontiguousarray(scattering_all[:, batch]), source, res.density_phi)
            del source
            previous, previous_phase, use_phase = delta[..., None, :], smooth_b, False
            order_mean[order - 1, batch], order_zenith[order - 1, batch] = to_full * (
                _table_build_kernels.order_statistics(previous, False, phase_b, order_grid))
            sums.add(delta)
            _check_converging(order_mean[:order, batch], wavelengths[batch])
            tail = _geometric_tail(order_mean[:order, batch], last=order == orders)
            orders_computed = max(orders_computed, order)
            extrapolated = None
            if tail is not None:
                # orders > n as the geometric series of order n (module docstring)
                factor = (tail / (1.0 - tail)).astype(np.float32)
                delta *= factor  # in place: the last order is not read again
                sums.add(delta)
                irradiance[..., batch] += delta_irradiance * factor
                tail_share[batch] = (order_mean[order - 1, batch] * factor
                                     / order_mean[1:order, batch].sum(axis=0))
            else:
                # or the orders' limit by reduced-rank extrapolation (`order_extrapolation`)
                extrapolated = extrapolation.add(order, sums.partial, delta, delta_irradiance)
                if extrapolated is not None:
                    multiple_tail, irradiance_tail = extrapolated
                    sums.add(multiple_tail)
                    irradiance[..., batch] += irradiance_tail
                    tail_mean, _ = to_full * _table_build_kernels.order_statistics(
                        multiple_tail[..., None, :], False, phase_b, order_grid)
                    tail_share[batch] = tail_mean / order_mean[1:order, batch].sum(axis=0)
                    del multiple_tail
            if tail is not None or extrapolated is not None:
                step += orders - order
                report(f"order {order} and the tail of the orders beyond, {label}")
                break
            report(f"order {order}, {label}")
            if on_order is not None:
                multiple = scattering[..., multiple_slot, :]
                if sums.coarse:
                    multiple = multiple.copy()
                    multiple[..., batch] = sums.on_tables_grid()
                on_order(order, batch, _read_only(multiple), _read_only(irradiance))
        sums.finish()
        del previous, delta, sums

    tables = AtmosphereTables(
        wavelengths_nm=wavelengths.copy(), bottom_radius_m=bottom, top_radius_m=top,
        min_cos_sun_zenith=mu_s_min, resolution=res, orders=orders,
        scattering_names=tuple(profile.names[c] for c in scatterers),
        scattering_constituents=scatterers,
        peak_correction_names=tuple(profile.names[scatterers[s]] for s in clipped),
        transmittance=transmittance,
        scattering=scattering, irradiance=irradiance, phase=phase,
        peak_correction_phase=np.ascontiguousarray(smooth_phase[clipped]),
        order_mean_radiance=order_mean, order_zenith_radiance=order_zenith,
        orders_computed=orders_computed, tail_share=tail_share,
        peak_transmittance=peak_transmittance, aureole_shape=aureole.shape,
        aureole_blur=aureole.blur,
        aureole_limits=np.array([aureole.x_max, aureole.psi_max_rad]), radius_warp=warp,
        sun_angle_share=grid.sun_angle_share)
    if gains is not None and orders > 1:
        # the same peaks' spread of the lines of sight, where that of the sun's beam is trusted
        _add_sight_spread(tables, profile, scaled, (peak_phase, res.truncation_angle_deg), grid,
                          _table_build_kernels.RayMedium(
                              h_step=h_step, density=density, columns=columns,
                              extinction=profile.extinction_per_density, cumulative=cumulative),
                          batches)
    return tables


def _add_sight_spread(tables: AtmosphereTables, profile: OpticalProfile,
                      scaled: _ScaledOptics, blur: tuple[np.ndarray, float],
                      grid: _table_build_kernels.TableGrid,
                      medium: _table_build_kernels.RayMedium, batches: list[slice]) -> None:
    """Add to the orders >= 2 of `tables` (in place) the peaks' spread of the lines of sight
    (`sight_spread`): the field F, the orders >= 2 (the peak corrections with their phase
    functions included) and the ground lit by the true sun and the sky (`tables.irradiance`),
    read on the scattering-density grid with `sight_spread`'s view zenith angles, its blur's
    source integrated along the table rays through the scaled medium with the peak scattering
    f beta_s as the scattering coefficient. `medium`: the true
    medium, all wavelengths; `blur`: (normalised peak, truncation angle [deg]) as
    `sight_spread_source`."""
    res = tables.resolution
    n_s = len(tables.scattering_constituents)
    theta = view_zenith_angles()
    phi = np.linspace(0.0, np.pi, res.density_phi)
    _, ground_mu_s = _node_positions(irradiance_r_mu_s_from_x, res.irradiance_mu_s,
                                     res.irradiance_r, grid.bottom_radius, grid.top_radius)
    samples = np.linspace(-1.0, 1.0, DIRECT_GROUND_SAMPLES)
    multiple = tables.scattering[..., -1, :]
    corrected = tables.scattering[..., n_s:, :]  # the peak corrections D_c, then M
    for batch in batches:
        true = medium._replace(extinction=np.ascontiguousarray(medium.extinction[:, batch]))
        sun = np.ascontiguousarray(profile.toa_irradiance[batch], dtype=np.float64)
        ground = _table_build_kernels.direct_ground_irradiance(
            DIRECT_GROUND_SAMPLES, grid, true, sun, float(profile.sun_angular_radius_rad))
        ground += np.stack([np.interp(samples, ground_mu_s[0], tables.irradiance[0, :, w])
                            for w in range(batch.start, batch.stop)], axis=1)
        field = _table_build_kernels.incoming_radiance(
            grid, true, theta, phi, _table_build_kernels.LitOrder(
                tables=flat_tables(corrected[..., batch]), n_t=corrected.shape[4],
                use_phase=True, phase_table=np.ascontiguousarray(
                    tables.peak_correction_phase[:, :, batch])),
            ground, np.ascontiguousarray(profile.ground_albedo[batch], dtype=np.float64),
            (0, grid.n_r))
        source = sight_spread_source(field, grid.n_mu_s, res.density_phi,
                                     (blur[0][:, batch], blur[1]))
        del field
        scaled_medium = true._replace(
            extinction=np.ascontiguousarray(scaled.extinction[:, batch]))
        spread = _table_build_kernels.multiple_scattering_table(
            grid, scaled_medium, res.multiple_ray_samples,
            np.ascontiguousarray(scaled.removed[:, batch]), source, res.density_phi)
        # first order in the peak events: where it would take more than M holds, M is 0
        multiple[..., batch] = np.maximum(multiple[..., batch] + spread, 0.0)


def _peak_aureole(profile: OpticalProfile, scaled: _ScaledOptics, scatterers: np.ndarray,
                  peak_phase: np.ndarray, smooth_phase: np.ndarray, peak: np.ndarray,
                  columns: np.ndarray, truncation_angle_deg: float
                  ) -> tuple[np.ndarray, PeakAureole]:
    """(exp(-x) (n_r_t, n_mu_t, n_wl) with x the peak depth f beta_s along the transmittance
    table's rays, the aureole of the peaks' multiple scattering and their blur of light
    scattered once in the smooth part) (`transport.aureole`); the peaks of several
    constituents mixed by their vertical peak depths, the smooth phase functions of the
    clipped constituents by their vertical smooth scattering depths. Without a clipped peak a
    transmittance of 1 and an aureole of angle 0 (nothing to add)."""
    n_wl = profile.n_wavelengths
    if not np.any(peak > 0.0):
        nothing = np.zeros((2, 2, n_wl))
        return np.ones((2, 2, n_wl)), PeakAureole(nothing, nothing, 1.0, 0.0)
    depth = np.einsum("cw,crm->rmw", scaled.removed, columns)
    column = profile.density[scatterers].sum(axis=1)[:, None]
    vertical = scaled.removed[scatterers] * column
    smooth_vertical = np.where(peak > 0.0, scaled.scattering[scatterers], 0.0) * column
    tiny = np.finfo(float).tiny
    smooth_share = smooth_vertical / np.maximum(smooth_vertical.sum(axis=0), tiny)
    aureole = peak_aureole(
        peak_phase, truncation_angle_deg, float(depth.max()),
        smooth_phase=np.einsum("sw,saw->aw", smooth_share, smooth_phase),
        smooth_ratio=smooth_vertical.sum(axis=0) / np.maximum(vertical.sum(axis=0), tiny))
    return np.exp(-np.minimum(depth, aureole.x_max)), aureole


def _mixed_peak(profile: OpticalProfile, scaled: _ScaledOptics, scatterers: np.ndarray,
                phase: np.ndarray, smooth_phase: np.ndarray, peak: np.ndarray) -> np.ndarray:
    """The normalised peaks p_peak = (p - (1 - f) p*) / f of the clipped constituents
    `scatterers` (phase functions (n_s, n_angle, n_wl)), mixed by their vertical peak depths:
    (n_angle, n_wl) [sr^-1], 0 where nothing is clipped."""
    vertical = scaled.removed[scatterers] * profile.density[scatterers].sum(axis=1)[:, None]
    share = vertical / np.maximum(vertical.sum(axis=0), np.finfo(float).tiny)  # (n_s, n_wl)
    with np.errstate(divide="ignore", invalid="ignore"):
        peak_phase = np.where(peak[:, None, :] > 0.0,
                              (phase - (1.0 - peak[:, None, :]) * smooth_phase)
                              / peak[:, None, :], 0.0)
    return np.einsum("sw,saw->aw", share, peak_phase)


class _BeamGains(NamedTuple):
    """G of `beam_spread` where the tables apply it: on the transmittance table's nodes
    (n_r_t, n_mu_t, n_wl), on horizontal surfaces on the irradiance table's nodes (n_r_e,
    n_mu_s_e, n_wl) and on the ground at the second order's sun samples
    (DIRECT_GROUND_SAMPLES, n_wl)."""

    transmittance: np.ndarray
    irradiance: np.ndarray
    ground: np.ndarray


def _beam_gains(spread: BeamSpread | None, res: TableResolution, bottom: float, top: float
                ) -> _BeamGains | None:
    """`spread`'s G on the tables' nodes (`_BeamGains`), once for all wavelengths; None
    without one."""
    if spread is None:
        return None
    r, mu = _node_positions(transmittance_r_mu_from_x, res.transmittance_mu,
                            res.transmittance_r, bottom, top)
    r_e, mu_s = _node_positions(irradiance_r_mu_s_from_x, res.irradiance_mu_s,
                                res.irradiance_r, bottom, top)
    return _BeamGains(spread.beam_at(r - bottom, mu), spread.irradiance_at(r_e - bottom, mu_s),
                      spread.irradiance_at(np.zeros(DIRECT_GROUND_SAMPLES),
                                           np.linspace(-1.0, 1.0, DIRECT_GROUND_SAMPLES)))


def _node_positions(inverse: Callable[[float, float, float, float], tuple[float, float]],
                    n_mu: int, n_r: int, bottom: float, top: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(r [m], mu) (n_r, n_mu) of a table's nodes: node (i, j) at x_r = i / (n_r - 1),
    x_mu = j / (n_mu - 1), placed by `inverse(x_mu, x_r, bottom, top)`
    (`table_parameterisation`)."""
    r, mu = np.array([[inverse(j / (n_mu - 1), i / (n_r - 1), bottom, top)
                       for j in range(n_mu)] for i in range(n_r)]).transpose(2, 0, 1)
    return r, mu


def _last_ratios(order_mean: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(order n / order n - 1, order n - 1 / order n - 2) per wavelength of `order_mean`
    (n, n_b), n >= 3; NaN or inf where an order is 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return order_mean[-1] / order_mean[-2], order_mean[-2] / order_mean[-3]


def _check_converging(order_mean: np.ndarray, wavelengths_nm: np.ndarray) -> None:
    """Raise InputError when the orders grow (`order_mean` (n, n_b), orders 1 .. n): each of
    the last two at least `DIVERGING_RATIO` times the one before, from order TAIL_MIN_ORDER on.
    Light cannot grow from order to order, and with the ray integrals in optical depth
    (`_table_build_kernels._ray_weights`) no shipped preset makes it; a safety net for what
    the tables cannot resolve (the trapezoid rule they used before made fog's orders grow)."""
    n = order_mean.shape[0]
    if n < TAIL_MIN_ORDER:
        return
    ratio, before = _last_ratios(order_mean)
    growing = (ratio >= DIVERGING_RATIO) & (before >= DIVERGING_RATIO)
    if np.any(growing):
        w = int(np.argmax(growing))
        raise InputError(
            f"the tables' scattering orders grow instead of converging (order {n} is "
            f"{ratio[w]:.2f} x order {n - 1} at {wavelengths_nm[w]:g} nm): this atmosphere has "
            "an optically thick layer thinner than the tables resolve (fog, a low cloud deck); "
            "use --solver montecarlo for it", key="orders", value=n,
            allowed="an atmosphere whose thick layers the tables resolve")


def _geometric_tail(order_mean: np.ndarray, last: bool) -> np.ndarray | None:
    """The ratio r (n_b,) of successive orders once it has settled, when the orders beyond the
    last computed one (`order_mean` (n, n_b), orders 1 .. n) are to be added as a geometric
    series: at the last order allowed, in every wavelength whose ratio has settled (0 in the
    others: nothing added, whatever wavelengths share the batch), or earlier, in all, when that
    tail's uncertainty is below `TAIL_TOLERANCE` and the tail itself below `TAIL_SHARE_MAX` of
    the orders >= 2 in every wavelength (module constants); None to go on."""
    if order_mean.shape[0] < TAIL_MIN_ORDER:
        return None
    ratio, before = _last_ratios(order_mean)
    with np.errstate(invalid="ignore"):
        each = (np.isfinite(ratio) & (ratio < 1.0) & (ratio >= 0.0)
                & (np.abs(ratio - before) <= RATIO_SETTLED * ratio))
    if last:
        return np.where(each, ratio, 0.0) if np.any(each) else None
    if not np.all(each):
        return None
    share = order_mean[-1] * ratio / (1.0 - ratio) / order_mean[1:].sum(axis=0)
    # d(r / (1 - r)) / (r / (1 - r)) = dr / (r (1 - r)); 0 where the orders are 0
    relative_change = np.abs(ratio - before) / np.maximum(ratio, np.finfo(float).tiny)
    uncertainty = share * relative_change / (1.0 - ratio)
    known = np.all(uncertainty <= TAIL_TOLERANCE) and np.all(share <= TAIL_SHARE_MAX)
    return ratio if known else None


def radius_warp(profile: OpticalProfile) -> np.ndarray:
    """The scattering table's radius warp W (RADIUS_WARP_SEGMENTS + 1,) at x = rho / H
    uniform in [0, 1] (`table_parameterisation.scattering_u_r`): W(x) = (1 - s) x + s G(x) /
    G(1), G(x) = int_0^tau(x) dt / (1 + d(t) / EDGE_OPTICAL_DEPTH), tau(x) the vertical optical
    depth from the ground up to x at the wavelength where a cell of Bruneton's axis (32 cells
    uniform in x) holds the most, tau_max, and d(t) = min(t, tau_top - t) the optical distance
    to the nearer end of the column; s = THICK_CELL_SHARE (1 - THICK_OPTICAL_DEPTH / tau_max)
    where tau_max exceeds THICK_OPTICAL_DEPTH, else 0 (the identity: Bruneton's axis). The
    cells crowd inside optically thick layers (clouds, fog), most at their edges."""
    x = np.linspace(0.0, 1.0, RADIUS_WARP_SEGMENTS + 1)
    level_x, depth, cell_depth = _reference_cells(profile)
    thickest = int(np.argmax(cell_depth.max(axis=1)))
    tau_max = float(cell_depth[thickest].max())
    if not tau_max > THICK_OPTICAL_DEPTH:
        return x
    share = THICK_CELL_SHARE * (1.0 - THICK_OPTICAL_DEPTH / tau_max)
    fine = np.linspace(0.0, 1.0, RADIUS_WARP_FINE + 1)
    tau = np.interp(fine, level_x, depth[:, thickest])
    density = 1.0 / (1.0 + np.minimum(tau, tau[-1] - tau) / EDGE_OPTICAL_DEPTH)
    crowded = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1])
                                               * np.diff(tau))])
    warp = (1.0 - share) * x + share * np.interp(x, fine, crowded) / crowded[-1]
    warp[-1] = 1.0
    return warp


def _reference_cells(profile: OpticalProfile) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x = rho / H of the profile's levels (n_z,), the vertical optical depth below each level
    (n_z, n_wl), the optical depth each cell of Bruneton's radius axis holds (n_wl,
    REFERENCE_RADIUS_CELLS))."""
    h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
    depth = _kernels.cumulative_columns(profile.density, h_step).T @ profile.extinction_per_density
    bottom, top = float(profile.bottom_radius_m), float(profile.top_radius_m)
    radius = bottom + profile.altitudes_m
    level_x = np.sqrt(np.maximum(radius**2 - bottom**2, 0.0) / (top**2 - bottom**2))
    cells = np.linspace(0.0, 1.0, REFERENCE_RADIUS_CELLS + 1)
    cell_depth = np.diff(np.array([np.interp(cells, level_x, d) for d in depth.T]), axis=1)
    return level_x, depth, cell_depth


def cubic_source(profile: OpticalProfile) -> bool:
    """Whether the tables of `profile` interpolate the source function cubically in radius
    (`_table_build_kernels.radius_taps`): where a cell of Bruneton's radius axis holds more
    than CUBIC_SOURCE_OPTICAL_DEPTH at some wavelength."""
    return bool(_reference_cells(profile)[2].max() > CUBIC_SOURCE_OPTICAL_DEPTH)


def is_identity_warp(warp: np.ndarray) -> bool:
    """Whether `warp` is Bruneton's radius axis (no optically thick layer)."""
    return bool(np.array_equal(warp, np.linspace(0.0, 1.0, warp.size)))


def sun_angle_share(profile: OpticalProfile, warp: np.ndarray) -> float:
    """The share of the mu_s axis uniform in sin(sun zenith / 2), nearly in the angle
    (`table_parameterisation.scattering_u_mu_s`): THICK_SUN_ANGLE_SHARE where `warp`
    (`radius_warp`) has an optically thick layer or `profile` optically significant
    forward-scattering particles (`has_forward_particles`), else 0 (Bruneton's axis)."""
    return 0.0 if is_clear(profile, warp) else THICK_SUN_ANGLE_SHARE


def is_clear(profile: OpticalProfile, warp: np.ndarray) -> bool:
    """Whether `profile` has neither an optically thick layer (`warp`, `radius_warp`, is
    Bruneton's axis) nor optically significant forward-scattering particles
    (`has_forward_particles`)."""
    return is_identity_warp(warp) and not has_forward_particles(profile)


def thick_layer_resolution(resolution: TableResolution, warp: np.ndarray) -> TableResolution:
    """`resolution` with at least THICK_LAYER_QUADRATURE where `warp` (`radius_warp`) crowds
    the radius cells into optically thick layers (module constants); unchanged otherwise."""
    if is_identity_warp(warp):
        return resolution
    return replace(resolution, **{
        name: max(getattr(resolution, name), value)
        for name, value in THICK_LAYER_QUADRATURE.items()})


def forward_scattering_resolution(resolution: TableResolution, profile: OpticalProfile,
                                  warp: np.ndarray) -> TableResolution:
    """`resolution` with at least FORWARD_NU_SLICES view-sun slices where forward-scattering
    particles of `profile` are optically significant and `warp` (`radius_warp`) has no thick
    layer, or one at the ground (module constants); unchanged otherwise."""
    if resolution.scattering_nu >= FORWARD_NU_SLICES:
        return resolution
    if not is_identity_warp(warp) and not _ground_in_thick_layer(profile):
        return resolution
    if not has_forward_particles(profile):
        return resolution
    return replace(resolution, scattering_nu=FORWARD_NU_SLICES)


def has_forward_particles(profile: OpticalProfile) -> bool:
    """Whether the particles of `profile` whose asymmetry parameter is at least
    FORWARD_ASYMMETRY hold a vertical scattering optical depth of at least
    FORWARD_OPTICAL_DEPTH at any of its wavelengths (module constants)."""
    scatterers = list(scattering_constituents(profile))
    if not scatterers:
        return False
    wavelengths = profile.wavelengths_nm
    asymmetry = np.array([profile.phases[c].asymmetry(wavelengths) for c in scatterers])
    h_step = float(profile.altitudes_m[1] - profile.altitudes_m[0])
    column = _kernels.cumulative_columns(profile.density[scatterers], h_step)[:, -1]
    depth = column[:, None] * profile.scattering_per_density[scatterers]  # (n_s, n_wl)
    forward = np.where(asymmetry >= FORWARD_ASYMMETRY, depth, 0.0).sum(axis=0)
    return bool(np.any(forward >= FORWARD_OPTICAL_DEPTH))


def _ground_in_thick_layer(profile: OpticalProfile) -> bool:
    """Whether the extinction at the ground is at least GROUND_LAYER_SHARE of the column's
    largest, at the wavelength of the largest vertical optical depth (fog, not a cloud deck)."""
    extinction = profile.density.T @ profile.extinction_per_density  # (n_z, n_wl)
    thickest = int(np.argmax(extinction.sum(axis=0)))
    column = extinction[:, thickest]
    return bool(column[0] >= GROUND_LAYER_SHARE * column.max())


@dataclass(frozen=True)
class _ScaledOptics:
    """Extinction and scattering per density (n_c, n_wl) of the delta-M scaled medium, and
    the scattering per density its truncated peaks take out, f beta_s."""

    extinction: np.ndarray
    scattering: np.ndarray
    removed: np.ndarray


def _scaled_optics(profile: OpticalProfile, scatterers: np.ndarray, peak: np.ndarray
                   ) -> _ScaledOptics:
    """beta_e* = beta_e - f beta_s and beta_s* = (1 - f) beta_s per density for the
    scattering constituents `scatterers` with peak fractions `peak` (n_s, n_wl)
    (`phase_truncation`); the other constituents unchanged."""
    removed = np.zeros_like(profile.scattering_per_density)
    removed[scatterers] = peak * profile.scattering_per_density[scatterers]
    return _ScaledOptics(np.ascontiguousarray(profile.extinction_per_density - removed),
                         np.ascontiguousarray(profile.scattering_per_density - removed),
                         removed)


def _coarse_grid(res: TableResolution, grid: _table_build_kernels.TableGrid
                 ) -> tuple[TableResolution, _table_build_kernels.TableGrid, _Resampling,
                            _Resampling] | None:
    """(resolution, grid, restriction, prolongation) of the coarse orders' grid
    (`coarse_resolution`); the last two interpolate from the fine grid to it and back. None
    when the mu axis is too short to halve."""
    coarse = coarse_resolution(res)
    if coarse is None:
        return None
    n_mu, n_nu = res.scattering_mu, res.scattering_nu
    coarse_mu, coarse_nu = coarse.scattering_mu, coarse.scattering_nu
    return (coarse, grid._replace(n_mu=coarse_mu, n_nu=coarse_nu),
            _Resampling(_mu_resampling(n_mu, coarse_mu), _linear_resampling(n_nu, coarse_nu)),
            _Resampling(_mu_resampling(coarse_mu, n_mu), _linear_resampling(coarse_nu, n_nu)))


def _sphere_integral(phase: np.ndarray, res: TableResolution
                     ) -> tuple[PhaseQuadrature, np.ndarray, np.ndarray]:
    """(phase matrices of `phase` (n_s, n_angle, n_b), the incoming directions' polar and
    azimuth angles) of the orders' sphere integral on the sphere of `res`."""
    theta_in, phi_in, *_ = sphere_grids(res)
    return phase_quadrature(phase, res), theta_in, phi_in


def coarse_resolution(res: TableResolution) -> TableResolution | None:
    """The resolution of the orders from `COARSE_FROM_ORDER` (`CLEAR_COARSE_FROM_ORDER`) on:
    half the view-zenith cells of `res`, COARSE_NU_SLICES view-sun slices, at most
    COARSE_SPHERE_THETA x COARSE_SPHERE_PHI incoming directions. None when the mu axis is too
    short to halve."""
    n_mu = res.scattering_mu
    if n_mu % 4 or n_mu < 16:
        return None
    return replace(res, scattering_mu=n_mu // 2,
                   scattering_nu=min(res.scattering_nu, COARSE_NU_SLICES),
                   sphere_theta=min(res.sphere_theta, COARSE_SPHERE_THETA),
                   sphere_phi=min(res.sphere_phi, COARSE_SPHERE_PHI))


class _FirstOrders(NamedTuple):
    """The sun tables and factors of the exact and the delta-M scaled medium's first orders
    (`_table_build_kernels.single_scattering_table`)."""

    sun_table: np.ndarray
    factor: np.ndarray
    scaled_sun_table: np.ndarray
    scaled_factor: np.ndarray

    def compute(self, grid: _table_build_kernels.TableGrid,
                medium: _table_build_kernels.RayMedium,
                scaled_medium: _table_build_kernels.RayMedium, n_samples: int, thick: bool,
                scatterers: np.ndarray, sun_radius: float, single: np.ndarray,
                scaled_single: np.ndarray) -> None:
        """Fill `single` and, unless it is empty, `scaled_single`: in one pass on the same ray
        samples, or, with an optically thick layer, where each medium places its own samples
        (refined and cut off by its own optical depths), in one pass each."""
        build = _table_build_kernels.single_scattering_table
        none = np.empty((0,) * single.ndim, dtype=np.float32)
        if thick and scaled_single.size:
            build(grid, scaled_medium, n_samples, self.scaled_sun_table, thick, scatterers,
                  self.scaled_factor, sun_radius, scaled_single, scaled_medium.extinction,
                  self.scaled_sun_table, self.scaled_factor, none)
            scaled_single = none
        build(grid, medium, n_samples, self.sun_table, thick, scatterers, self.factor,
              sun_radius, single, scaled_medium.extinction, self.scaled_sun_table,
              self.scaled_factor, scaled_single)


class _OrderSums:
    """The sum of the orders >= 2 of one wavelength batch on the grid they are iterated on: a
    view of the tables until `coarsen`, then the coarse grid's (`_coarse_grid`), whose orders
    `finish` adds to the tables interpolated back, once."""

    def __init__(self, tables: np.ndarray) -> None:
        self.partial = tables
        self._tables = tables
        self._coarse_orders: np.ndarray | None = None  # the orders since `coarsen`
        self._prolong: _Resampling | None = None

    @property
    def coarse(self) -> bool:
        return self._coarse_orders is not None

    def coarsen(self, restrict: _Resampling, prolong: _Resampling) -> None:
        self.partial = _resampled(self._tables, restrict)
        self._coarse_orders = np.zeros_like(self.partial)
        self._prolong = prolong

    def add(self, delta: np.ndarray) -> None:
        self.partial += delta
        if self._coarse_orders is not None:
            self._coarse_orders += delta

    def on_tables_grid(self) -> np.ndarray:
        """The sum so far on the tables' grid."""
        if self._coarse_orders is None:
            return self._tables
        return self._tables + _resampled(self._coarse_orders, self._prolong)

    def finish(self) -> None:
        if self._coarse_orders is not None:
            # a radius at a time (`_resampled`)
            for k in range(self._tables.shape[0]):
                self._tables[k] += _resampled_radius(self._coarse_orders[k], self._prolong)
            self._coarse_orders = None


class _Resampling(NamedTuple):
    """Linear interpolation onto another u_mu and u_nu axis, each as (low, weight) (n_to,):
    entry i of the new axis is (1 - weight) old[low] + weight old[low + 1]."""

    mu: tuple[np.ndarray, np.ndarray]
    nu: tuple[np.ndarray, np.ndarray]


def _linear_resampling(n_from: int, n_to: int) -> tuple[np.ndarray, np.ndarray]:
    """Linear interpolation from n_from to n_to entries evenly spaced over [0, 1], as (low,
    weight) (`_Resampling`)."""
    position = np.arange(n_to) * (n_from - 1) / max(n_to - 1, 1)
    low = np.minimum(position.astype(np.int64), n_from - 2)
    return low, (position - low).astype(np.float32)


def _mu_resampling(n_from: int, n_to: int) -> tuple[np.ndarray, np.ndarray]:
    """`_linear_resampling` of the u_mu axis within each of its halves (the rays that hit the
    ground, those that do not), whose entry k of m sits at x = k / (m - 1)
    (`table_parameterisation.scattering_mu_from_u`)."""
    low, weight = _linear_resampling(n_from // 2, n_to // 2)
    return np.concatenate([low, n_from // 2 + low]), np.concatenate([weight, weight])


def _resampled(table: np.ndarray, resampling: _Resampling) -> np.ndarray:
    """A table (n_r, n_mu, n_mu_s, n_nu, n_b) on other mu and nu axes (`_Resampling`), a
    radius at a time (the whole table's intermediates would be as large as the table)."""
    n_r, _, n_mu_s, _, n_b = table.shape
    result = np.empty((n_r, resampling.mu[0].size, n_mu_s, resampling.nu[0].size, n_b),
                      dtype=table.dtype)
    for k in range(n_r):
        result[k] = _resampled_radius(table[k], resampling)
    return result


def _resampled_radius(table: np.ndarray, resampling: _Resampling) -> np.ndarray:
    """One radius (n_mu, n_mu_s, n_nu, n_b) of a table on other mu and nu axes."""
    for axis, (low, weight) in ((0, resampling.mu), (2, resampling.nu)):
        if low.size == table.shape[axis]:
            continue  # same size: the identity
        shape = [1] * table.ndim
        shape[axis] = low.size
        weight = weight.reshape(shape)
        result = np.take(table, low, axis=axis)
        result *= 1.0 - weight
        result += np.take(table, low + 1, axis=axis) * weight
        table = result
    return table


def _single_in_place(batch_tables: np.ndarray, single: np.ndarray, phase: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(tables, phase functions) of the single scattering as the second order reads it
    (`LitOrder`): in place in the tables when one batch holds all wavelengths (`batch_tables`
    (n_r, n_mu, n_mu_s, n_nu, n_s + 1, n_b) C-contiguous), the multiple-scattering slot, empty
    until the second order is added, weighed by a phase function of 0; else `single`, which
    `flat_tables` copies."""
    if not batch_tables.flags.c_contiguous:
        return single, phase
    return batch_tables, np.concatenate([phase, np.zeros_like(phase[:1])])


def _read_only(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view
