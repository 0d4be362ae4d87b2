"""The aureole of multiple forward-peak scattering (`transport.aureole`) against closed forms:
for a Gaussian peak of small width sigma the n-fold convolution on the sphere is, in the
small-angle limit, a Gaussian of variance n sigma^2, so the aureole's shape is a Poisson mixture
of Gaussians; and the shape integrates to 1 over the sphere. The peaks' blur of light scattered
once in a clipped smooth phase function against the same Poisson mixture of that function
convolved on the sphere by direct quadrature. The lookups' path from the sun
to the eye (`_table_lookup_kernels.aureole_path`): its integral over the events' depths
against the divided difference of exp (Hermite-Genocchi), and, looking at the sun, the line
of sight's closed form."""

import decimal
import math
from dataclasses import replace

import numpy as np
import pytest
from transport_cases import SMALL, exponential_earth

from skyscatter.transport._table_lookup_kernels import (
    AUREOLE_VIEW_CHI,
    AUREOLE_VIEW_PSI,
    SIMPLEX_WORK,
    simplex_exponential,
    transmittance_to_top,
)
from skyscatter.transport.aureole import peak_aureole
from skyscatter.transport.lut_solver import LutSolver

N_ANGLE = 4097  # the tables' sampling (TableResolution.phase_angles)
THETA = np.linspace(0.0, np.pi, N_ANGLE)
SIGMA = np.radians(1.0)
TRUNCATION_DEG = 10.0


def gaussian(psi: np.ndarray, variance: float) -> np.ndarray:
    """The small-angle 2-D Gaussian exp(-psi^2 / (2 v)) / (2 pi v) [sr^-1]."""
    return np.exp(-psi * psi / (2.0 * variance)) / (2.0 * np.pi * variance)


def mixture(psi: np.ndarray, x: float) -> np.ndarray:
    """sum_{n >= 2} x^n / n! N(n sigma^2)(psi) / (exp(x) - 1 - x)."""
    terms = [x ** n / math.factorial(n) * gaussian(psi, n * SIGMA ** 2) for n in range(2, 60)]
    return np.sum(terms, axis=0) / (math.expm1(x) - x)


@pytest.fixture(scope="module")
def aureole():
    peak = np.where(np.radians(TRUNCATION_DEG) > THETA, gaussian(THETA, SIGMA ** 2), 0.0)
    weight = 2.0 * np.pi * np.sin(THETA)
    peak /= np.trapezoid(peak * weight, THETA)
    return peak_aureole(peak[:, None], TRUNCATION_DEG, 20.0)


def x_nodes(aureole) -> np.ndarray:
    n_x = aureole.shape.shape[0]
    return np.expm1(np.log1p(aureole.x_max) * np.arange(n_x) / (n_x - 1))


def psi_nodes(aureole) -> np.ndarray:
    return np.linspace(0.0, aureole.psi_max_rad, aureole.shape.shape[1])


@pytest.mark.parametrize("node", [0, 20, 40])
def test_shape_is_the_poisson_mixture_of_widened_gaussians(aureole, node):
    x = max(x_nodes(aureole)[node], 1e-6)
    psi = psi_nodes(aureole)
    expected = mixture(psi, x)
    near = psi < np.radians(4.0)
    # small-angle limit: sin(psi) ~ psi to 0.1 % within 4 deg; the spherical convolution
    # differs from the planar one by O(sigma^2) = 3e-4
    np.testing.assert_allclose(aureole.shape[node, near, 0], expected[near],
                               rtol=5e-3, atol=1e-3 * expected[0])


def test_shape_integrates_to_one_while_the_angles_hold_it(aureole):
    psi = psi_nodes(aureole)
    x = x_nodes(aureole)
    energy = np.trapezoid(aureole.shape[:, :, 0] * 2.0 * np.pi * np.sin(psi), psi, axis=1)
    # up to x = 20 the widest term (n ~ 30: 5.5 deg rms) stays well inside psi_max = 30 deg
    np.testing.assert_allclose(energy[x <= 20.0], 1.0, atol=2e-3)


def test_no_peak_gives_no_aureole():
    empty = peak_aureole(np.zeros((N_ANGLE, 2)), TRUNCATION_DEG, 1.0)
    assert np.all(empty.shape == 0.0) and np.all(empty.blur == 0.0)


SMOOTH_RATIO = 0.7
SMOOTH_DECAY = np.radians(20.0)


def clipped_smooth(theta: np.ndarray) -> np.ndarray:
    """A clipped phase function's shape: flat inside the truncation angle, a kink there, an
    exponential beyond (not normalised)."""
    edge = np.radians(TRUNCATION_DEG)
    return np.where(theta < edge, 1.0, np.exp(-(theta - edge) / SMOOTH_DECAY))


SMOOTH_NORM = 1.0 / np.trapezoid(clipped_smooth(THETA) * 2.0 * np.pi * np.sin(THETA), THETA)


@pytest.fixture(scope="module")
def blurred():
    peak = np.where(np.radians(TRUNCATION_DEG) > THETA, gaussian(THETA, SIGMA ** 2), 0.0)
    weight = 2.0 * np.pi * np.sin(THETA)
    peak /= np.trapezoid(peak * weight, THETA)
    return peak_aureole(peak[:, None], TRUNCATION_DEG, 20.0,
                        smooth_phase=(SMOOTH_NORM * clipped_smooth(THETA))[:, None],
                        smooth_ratio=np.array([SMOOTH_RATIO]))


def smooth_convolved(psi: float, variance: float) -> float:
    """p* convolved on the sphere with the Gaussian of `variance` [rad^2], at psi: direct
    quadrature over the kernel's angles (midpoints; the kernel normalised on the same nodes)."""
    reach = min(6.0 * math.sqrt(variance), np.pi / 2.0)
    gamma = (np.arange(1500) + 0.5) * reach / 1500
    phi = (np.arange(360) + 0.5) * np.pi / 360
    cos_theta = (np.cos(psi) * np.cos(gamma)[:, None]
                 + np.sin(psi) * np.sin(gamma)[:, None] * np.cos(phi)[None])
    kernel = (np.exp(-gamma ** 2 / (2.0 * variance)) * np.sin(gamma))[:, None]
    smooth = SMOOTH_NORM * clipped_smooth(np.arccos(np.clip(cos_theta, -1.0, 1.0)))
    return float((kernel * smooth).sum() / (kernel.sum() * phi.size))


@pytest.mark.parametrize("node", [0, 20])
def test_blur_is_the_smooth_phase_convolved_with_the_poisson_mixture_of_peaks(blurred, node):
    # B(x, psi) = r (sum_n>=1 e^-x x^n / n! p* (*) p_peak^(n) - (1 - e^-x) p*), p_peak^(n) the
    # Gaussian of variance n sigma^2 (small-angle limit, as above)
    x = max(x_nodes(blurred)[node], 1e-6)
    psi = psi_nodes(blurred)[::7]
    smooth = SMOOTH_NORM * clipped_smooth(psi)
    expected = np.array([
        sum(math.exp(-x) * x ** n / math.factorial(n) * smooth_convolved(p, n * SIGMA ** 2)
            for n in range(1, 40)) for p in psi]) - (1.0 - math.exp(-x)) * smooth
    expected *= SMOOTH_RATIO
    assert np.abs(expected).max() > 1e-3 * x  # the kink's dip: -1.2 % of p* at x -> 0
    # measured 0.9 % (x -> 0) and 0.4 % (x = 1.6) of the dip: the spherical against the
    # planar convolution, O(sigma^2) relative, and the sampled p*'s moments
    np.testing.assert_allclose(blurred.blur[node, ::7, 0], expected,
                               atol=0.02 * np.abs(expected).max())


def divided_difference_of_exp(depths: list[float]) -> float:
    """int over the simplex sum g_k = 1 of exp(-sum_k d_k g_k) for distinct d_k, in closed form
    by the Hermite-Genocchi formula (de Boor 2005, "Divided differences", Surveys in
    Approximation Theory 1, 46, eq. 1.4): (-1)^n [d_0, .., d_n] exp(-d) =
    sum_k exp(-d_k) / prod_{j != k} (d_j - d_k), summed in 60-digit decimal arithmetic so that
    nodes 1e-9 apart lose nothing to cancellation."""
    with decimal.localcontext() as context:
        context.prec = 60
        nodes = [decimal.Decimal(d) for d in depths]
        total = sum((-d).exp() / math.prod(e - d for e in nodes if e != d) for d in nodes)
        return float(total)


# slant depths along the path from the sun to the eye: a sun 5 deg high seen 5 deg above it in
# dusty Mars, a hazy zenith, a horizon of optical depth 30, and nodes bunched together (nearly
# the line of sight's own direction) or bunched with one far off, where the recurrence of
# divided differences cancels and the Taylor series takes over
PATHS = [[4.2, 2.9, 1.75], [4.2, 3.3, 2.4, 1.75], [0.3, 0.2, 0.25, 0.1], [10.4, 7.0, 3.5],
         [30.0, 12.0, 5.0], [2.0, 2.0 + 1e-7, 2.0 + 2e-7, 2.3], [1.0, 1.4, 1.45, 30.0],
         [5.0, 5.6, 5.6 + 1e-9], [0.7, 0.2, 0.69, 0.71], [700.0, 3.0, 2.0]]


@pytest.mark.parametrize("depths", PATHS)
def test_the_path_integral_over_the_events_depths_is_the_divided_difference(depths):
    value = simplex_exponential(np.array(depths), len(depths) - 1, np.empty(SIMPLEX_WORK))
    # double precision less what the recurrence's cancellation costs (1e-15 / spans of 0.5)
    assert value == pytest.approx(divided_difference_of_exp(depths), rel=1e-12)


@pytest.mark.parametrize("n", [1, 2, 3])
def test_one_direction_gives_the_poisson_term_of_the_line_of_sight(n):
    value = simplex_exponential(np.full(n + 1, 2.5), n, np.empty(SIMPLEX_WORK))
    # exp(-x) / n!: all gaps crossed with the same depth
    assert value == pytest.approx(math.exp(-2.5) / math.factorial(n), rel=1e-14)


@pytest.fixture(scope="module")
def hazy_lut():
    """Tables of a Rayleigh + HG 0.8 haze atmosphere at the default truncation (15 deg), small
    sizes: its haze has a clipped peak, so the lookups add the aureole."""
    profile = exponential_earth()
    return LutSolver(profile, SMALL, orders=2)


def aureole_alone(lut: LutSolver, views: np.ndarray, sun: np.ndarray,
                  origin: np.ndarray | None = None) -> np.ndarray:
    """The aureole term of the lookups along `views` (n, 3) from `origin` (default: 100 m above
    the ground; (n, 3) for one origin per ray): the sky with it less the sky of the same tables
    without it (aureole angle 0)."""
    if origin is None:
        origin = np.array([0.0, 0.0, lut.tables.bottom_radius_m + 100.0])
    limits = lut.tables.aureole_limits * np.array([1.0, 0.0])
    without = LutSolver(lut.profile, tables=replace(lut.tables, aureole_limits=limits))
    return lut.sky_radiance(origin, views, sun) - without.sky_radiance(origin, views, sun)


def test_towards_the_sun_the_aureole_is_the_line_of_sight_closed_form(hazy_lut):
    t = hazy_lut.tables
    sun_zenith = np.radians(80.0)
    sun = np.array([np.sin(sun_zenith), 0.0, np.cos(sun_zenith)])
    value = aureole_alone(hazy_lut, sun[None], sun)[0]
    r, mu = t.bottom_radius_m + 100.0, float(np.cos(sun_zenith))
    through, peak = np.empty(3), np.empty(3)
    transmittance_to_top(r, mu, t.bottom_radius_m, t.top_radius_m, t.transmittance, through)
    transmittance_to_top(r, mu, t.bottom_radius_m, t.top_radius_m, t.peak_transmittance, peak)
    x = -np.log(peak)
    x_max = t.aureole_limits[0]
    n_x = t.aureole_shape.shape[0]
    node = np.log1p(x) / np.log1p(x_max) * (n_x - 1)
    shape, blur = (np.array([np.interp(node[w], np.arange(n_x), table[:, 0, w])
                             for w in range(3)]) for table in (t.aureole_shape, t.aureole_blur))
    expected = hazy_lut.profile.toa_irradiance * through * (
        (np.expm1(x) - x) * shape + np.exp(x) * x * blur)
    assert np.all(expected > 0.0) and np.all(blur != 0.0)
    # the same path in every direction: x' = x up to the trapezoid rule (1e-4)
    np.testing.assert_allclose(value, expected, rtol=1e-3)



def test_one_observers_aureole_from_its_view_table_matches_the_path_of_each_ray(hazy_lut):
    # One observer's frame takes the path's Poisson law from a table over the angles from and
    # about the sun (`aureole_view_table`); rays of many origins compute it per ray
    # (`aureole_path`). The same observer both ways, views up to the aureole's reach psi_max:
    # bilinear interpolation of depths that change over degrees, on cells of 0.47 x 2.8 deg.
    t = hazy_lut.tables
    psi_max = t.aureole_limits[1]
    origin = np.array([0.0, 0.0, t.bottom_radius_m + 100.0])
    rng = np.random.default_rng(7)
    for sun_zenith_deg in (0.0, 30.0, 60.0, 80.0):
        theta_s = np.radians(sun_zenith_deg)
        sun = np.array([np.sin(theta_s), 0.0, np.cos(theta_s)])
        psi = psi_max * np.sqrt(rng.uniform(0.0, 1.0, 16_000))
        chi = rng.uniform(0.0, 2.0 * np.pi, 16_000)
        e1 = np.cross(sun, [0.0, 1.0, 0.0]) if sun_zenith_deg else np.array([1.0, 0.0, 0.0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(sun, e1)
        views = (np.cos(psi)[:, None] * sun + np.sin(psi)[:, None]
                 * (np.cos(chi)[:, None] * e1 + np.sin(chi)[:, None] * e2))
        views = views[views[:, 2] > 0.02]  # the aureole is for rays that miss the ground
        # a call with fewer rays than the table's nodes computes the path per ray
        assert len(views) >= AUREOLE_VIEW_PSI * AUREOLE_VIEW_CHI
        table = aureole_alone(hazy_lut, views, sun)
        per_ray = aureole_alone(hazy_lut, views, sun, np.repeat(origin[None], len(views), 0))
        sky = hazy_lut.sky_radiance(origin, views, sun)
        # (negative where the peaks' blur darkens the clipped phase function's kink)
        assert per_ray.max() > 0.0
        error = np.abs(table - per_ray)
        # the sky radiance within 0.01 % (measured: at most 3e-6 of it, next to the horizon
        # with the sun 80 deg from the zenith), the aureole itself within 0.1 % (median)
        assert np.all(error <= 1e-4 * sky)
        assert np.median(error / np.abs(per_ray)) < 1e-3
