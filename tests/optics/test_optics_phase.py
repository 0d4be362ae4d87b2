"""Phase functions: normalisation, asymmetry, limits, shapes and use inside numba kernels."""

import numpy as np
import pytest
from numba import njit
from scipy.integrate import quad, quad_vec

from skyscatter.errors import InputError
from skyscatter.optics.phase import (
    CornetteShanksPhase,
    DoubleHenyeyGreensteinPhase,
    HenyeyGreensteinPhase,
    PenndorfPhase,
    PhaseFunction,
    RayleighPhase,
    TabulatedPhase,
    angle_blended_phase,
    cornette_shanks,
    cornette_shanks_asymmetry,
    double_henyey_greenstein,
    henyey_greenstein,
    penndorf,
    rayleigh,
)
from skyscatter.spectrum.tabulated import SpectralParameter

WL = np.array([440.0, 550.0, 680.0])
G_VALUES = [-0.7, -0.3, 0.0, 0.3, 0.761, 0.9, 0.95]


def solid_angle_integral(p, weight=lambda nu: 1.0):
    """2 pi int_-1^1 p(nu) w(nu) dnu by adaptive quadrature (scipy quad, rel. error 1e-11).

    The HG forward peak at g = 0.95 is ~(1-g)^2 wide in nu; quad's adaptive bisection resolves
    it (limit=500 intervals)."""
    value, _ = quad(lambda nu: 2.0 * np.pi * p(nu) * weight(nu), -1.0, 1.0, epsabs=1e-13,
                    epsrel=1e-11, limit=500)
    return value


# --- identities of the kernels ---------------------------------------------------------------

def test_rayleigh_integrates_to_one():
    # Identity: a phase function integrates to 1 over 4 pi sr. Quadrature error only (1e-10).
    assert solid_angle_integral(rayleigh) == pytest.approx(1.0, abs=1e-10)


def test_penndorf_integrates_to_its_published_0p99992():
    # Closed form of Costa 2020 Eq. 10 as printed: 0.7629 (1 + 0.932/3) = 0.99991; it is 1e-4
    # short of 1 because Penndorf's constants are rounded.
    integral = solid_angle_integral(penndorf)
    assert integral == pytest.approx(0.7629 * (1.0 + 0.932 / 3.0), abs=1e-10)
    assert integral == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("g", G_VALUES)
def test_henyey_greenstein_normalised_with_mean_cosine_g(g):
    # Identities: int p = 1 and <nu> = g (Henyey & Greenstein 1941). Quadrature error < 1e-9.
    assert solid_angle_integral(lambda nu: henyey_greenstein(nu, g)) == pytest.approx(1.0,
                                                                                      abs=1e-9)
    mean_cos = solid_angle_integral(lambda nu: henyey_greenstein(nu, g), lambda nu: nu)
    assert mean_cos == pytest.approx(g, abs=1e-9)


@pytest.mark.parametrize("g", G_VALUES)
def test_cornette_shanks_normalised_with_closed_form_asymmetry(g):
    # Identities: int p = 1; <nu> = 3 g (4 + g^2) / (5 (2 + g^2)). Quadrature error < 1e-9.
    assert solid_angle_integral(lambda nu: cornette_shanks(nu, g)) == pytest.approx(1.0,
                                                                                    abs=1e-9)
    mean_cos = solid_angle_integral(lambda nu: cornette_shanks(nu, g), lambda nu: nu)
    assert mean_cos == pytest.approx(float(cornette_shanks_asymmetry(g)), abs=1e-9)


@pytest.mark.parametrize("g1, g2, alpha", [(0.67, 0.094, 0.743), (0.9, -0.4, 0.95),
                                           (0.03, 0.094, 0.0)])
def test_double_henyey_greenstein_normalised_with_weighted_asymmetry(g1, g2, alpha):
    # Costa 2020's Mars dust lobes and a forward/backward pair: int p = 1 and
    # <nu> = alpha g1 + (1 - alpha) g2 (both terms normalised; Costa's Eq. 16 typo avoided).
    p = lambda nu: double_henyey_greenstein(nu, g1, g2, alpha)  # noqa: E731
    assert solid_angle_integral(p) == pytest.approx(1.0, abs=1e-9)
    assert solid_angle_integral(p, lambda nu: nu) == pytest.approx(alpha * g1 + (1 - alpha) * g2,
                                                                   abs=1e-9)


def test_cornette_shanks_tends_to_rayleigh_as_g_goes_to_zero():
    # Closed form: at g = 0, k = 3/(16 pi) and the denominator is 1, so p = Rayleigh exactly;
    # for small g the difference is O(g): 1e-3 relative at g = 1e-4.
    nu = np.linspace(-1.0, 1.0, 101)
    np.testing.assert_allclose(cornette_shanks(nu, 0.0), rayleigh(nu), rtol=1e-15)
    np.testing.assert_allclose(cornette_shanks(nu, 1e-4), rayleigh(nu), rtol=1e-3)


def test_double_henyey_greenstein_with_alpha_one_is_henyey_greenstein():
    nu = np.linspace(-1.0, 1.0, 101)
    np.testing.assert_allclose(double_henyey_greenstein(nu, 0.8, -0.3, 1.0),
                               henyey_greenstein(nu, 0.8), rtol=1e-15)


def test_henyey_greenstein_forward_value_closed_form():
    # p(1; g) = (1 + g) / (4 pi (1 - g)^2): 1.5031 sr^-1 at g = 0.7.
    assert henyey_greenstein(1.0, 0.7) == pytest.approx(1.7 / (4 * np.pi * 0.09), rel=1e-14)


# --- kernels: shapes, numba, edges ------------------------------------------------------------

KERNELS = [
    lambda nu: rayleigh(nu),
    lambda nu: penndorf(nu),
    lambda nu: henyey_greenstein(nu, 0.7),
    lambda nu: double_henyey_greenstein(nu, 0.7, -0.2, 0.8),
    lambda nu: cornette_shanks(nu, 0.7),
]


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_kernels_keep_the_input_shape(kernel, shape):
    nu = np.full(shape, 0.25) if shape else 0.25
    out = kernel(nu)
    assert np.shape(out) == shape
    assert np.all(np.isfinite(out))


def test_kernels_broadcast_array_parameters():
    nu = np.linspace(-1.0, 1.0, 4)[:, None]
    g = np.array([0.1, 0.5, 0.9])
    out = henyey_greenstein(nu, g)
    assert out.shape == (4, 3)
    np.testing.assert_allclose(out[2, 1], henyey_greenstein(float(nu[2, 0]), 0.5), rtol=1e-15)


@njit(cache=False)
def _midpoint_integral(n, g):
    total = 0.0
    for i in range(n):
        nu = -1.0 + (i + 0.5) * 2.0 / n
        total += (rayleigh(nu) + penndorf(nu) + henyey_greenstein(nu, g)
                  + double_henyey_greenstein(nu, g, -g, 0.5) + cornette_shanks(nu, g))
    return 2.0 * np.pi * total * 2.0 / n


def test_kernels_are_callable_inside_numba_functions():
    # Five normalised functions (Penndorf 0.99991): midpoint rule with 20000 steps at g = 0.5
    # is exact to ~1e-7.
    assert _midpoint_integral(20000, 0.5) == pytest.approx(4.0 + 0.7629 * (1 + 0.932 / 3),
                                                           abs=1e-6)


@pytest.mark.parametrize("g", [-0.999, 0.999])
def test_kernels_finite_at_extreme_g_and_angles(g):
    for nu in (-1.0, 0.0, 1.0):
        for value in (henyey_greenstein(nu, g), cornette_shanks(nu, g),
                      double_henyey_greenstein(nu, g, -g, 0.5)):
            assert np.isfinite(value) and value > 0.0


# --- PhaseFunction objects --------------------------------------------------------------------

G_TABLE = SpectralParameter.table([440.0, 550.0, 680.0], [0.67, 0.4, 0.03])
OBJECTS = [
    RayleighPhase(),
    PenndorfPhase(),
    HenyeyGreensteinPhase(0.8),
    HenyeyGreensteinPhase(G_TABLE),
    DoubleHenyeyGreensteinPhase(G_TABLE, 0.094, 0.743),
    CornetteShanksPhase(SpectralParameter.table([440.0, 680.0], [0.9, 0.5])),
]


@pytest.mark.parametrize("phase", OBJECTS, ids=lambda p: type(p).__name__)
def test_phase_objects_normalised_and_asymmetry_matches_integral(phase):
    # Identities per wavelength: int p = 1 (Penndorf 0.99991) and <nu> = asymmetry(wl).
    assert isinstance(phase, PhaseFunction)
    norm, _ = quad_vec(lambda nu: 2 * np.pi * phase.evaluate(nu, WL), -1.0, 1.0, epsrel=1e-11)
    expected = 0.7629 * (1 + 0.932 / 3) if isinstance(phase, PenndorfPhase) else 1.0
    np.testing.assert_allclose(norm, expected, atol=1e-9)
    mean_cos, _ = quad_vec(lambda nu: 2 * np.pi * nu * phase.evaluate(nu, WL), -1.0, 1.0,
                           epsrel=1e-11)
    np.testing.assert_allclose(mean_cos / norm, phase.asymmetry(WL), atol=1e-9)


def test_dhg_costa_mars_asymmetry_values():
    # Costa 2020 (its OpenSpace code's values, Meyran 2022 Table 3.7): g1 = (0.67, 0.4, 0.03) at
    # (440, 550, 680) nm, g2 = 0.094, alpha = 0.743: <nu> = 0.743 g1 + 0.257 x 0.094, by hand.
    dhg = DoubleHenyeyGreensteinPhase(G_TABLE, 0.094, 0.743)
    np.testing.assert_allclose(dhg.asymmetry(WL), [0.521968, 0.321358, 0.046448], atol=1e-6)


@pytest.mark.parametrize("phase", OBJECTS, ids=lambda p: type(p).__name__)
@pytest.mark.parametrize("shape", [(), (5,), (2, 3)])
def test_phase_objects_return_shape_s_plus_n_wl(phase, shape):
    nu = np.full(shape, 0.3)
    out = phase.evaluate(nu, WL)
    assert out.shape == shape + (3,)
    assert phase.asymmetry(WL).shape == (3,)
    assert phase.evaluate(0.3, 550.0).shape == (1,)


def test_tabulated_phase_reproduces_henyey_greenstein_table():
    # A Mie-like table: HG(g) at 0.25° steps for two wavelengths. Log-linear interpolation in
    # angle reproduces HG between nodes to 0.1 %, its normalisation to 1e-6 (64 trapezoid
    # sub-steps) and <nu> to 1e-4.
    angles = np.linspace(0.0, 180.0, 721)
    nu_tab = np.cos(np.deg2rad(angles))
    g = np.array([0.85, 0.6])
    values = henyey_greenstein(nu_tab[:, None], g[None, :]) * 7.0  # arbitrary scale
    phase = TabulatedPhase(angles, values, [450.0, 650.0])
    wl = np.array([450.0, 550.0, 650.0])
    nu = np.cos(np.deg2rad([0.1, 3.3, 45.1, 120.7, 179.9]))
    expected = henyey_greenstein(nu[:, None], g[None, :])
    got = phase.evaluate(nu, wl)
    np.testing.assert_allclose(got[:, [0, 2]], expected, rtol=1e-3)
    np.testing.assert_allclose(got[:, 1], expected.mean(axis=1), rtol=1e-3)
    np.testing.assert_allclose(phase.asymmetry(wl), [0.85, 0.725, 0.6], atol=1e-4)
    norm, _ = quad_vec(lambda x: 2 * np.pi * phase.evaluate(x, wl), -1.0, 1.0, epsrel=1e-10,
                       points=nu_tab[::-1][1:-1][::40])
    np.testing.assert_allclose(norm, 1.0, atol=1e-5)


def test_tabulated_phase_grey_column_and_out_of_range_wavelengths():
    angles = np.linspace(0.0, 180.0, 181)
    phase = TabulatedPhase(angles, rayleigh(np.cos(np.deg2rad(angles))))
    np.testing.assert_allclose(phase.evaluate([1.0, 0.0], [300.0, 900.0]),
                               rayleigh(np.array([[1.0, 1.0], [0.0, 0.0]])), rtol=1e-4)
    assert abs(phase.asymmetry(550.0)[0]) < 1e-10


@pytest.mark.parametrize("make, message", [
    (lambda: HenyeyGreensteinPhase(1.0), r"g = \[1.0\] must lie in \(-1.0, 1.0\)"),
    (lambda: CornetteShanksPhase(-1.2), r"g = \[-1.2\] must lie in"),
    (lambda: DoubleHenyeyGreensteinPhase(0.5, 0.1, 1.5),
     r"alpha = \[1.5\] must lie in \[0.0, 1.0\]"),
    (lambda: TabulatedPhase([0.0, 90.0], [1.0, 1.0]), "increase strictly from 0 to 180"),
    (lambda: TabulatedPhase([0.0, 180.0], [1.0, 0.0]), "must be finite and > 0"),
    (lambda: TabulatedPhase([0.0, 180.0], np.ones((2, 2))), "wavelengths_nm is required"),
    (lambda: TabulatedPhase([0.0, 180.0], np.ones((2, 2)), [500.0]), "expected"),
])
def test_bad_phase_parameters_are_input_errors(make, message):
    with pytest.raises(InputError, match=message):
        make()


def test_angle_blended_phase_ends_and_normalisation():
    # Forward lobe at 0 deg, backward lobe at 180 deg, each up to the renormalisation, which
    # the blend's own 4 pi integral fixes.
    angles = np.concatenate([np.linspace(0.0, 5.0, 101), np.linspace(5.5, 180.0, 350)])
    wl = np.array([440.0, 680.0])
    forward = HenyeyGreensteinPhase(0.8)
    backward = HenyeyGreensteinPhase(-0.3)
    blend = angle_blended_phase(forward, backward, angles, wl)
    nu = np.cos(np.deg2rad(angles))
    raw = ((1 - angles / 180)[:, None] * forward.evaluate(nu, wl)
           + (angles / 180)[:, None] * backward.evaluate(nu, wl))
    norm = 2 * np.pi * np.trapezoid(raw * np.sin(np.deg2rad(angles))[:, None],
                                    np.deg2rad(angles), axis=0)
    np.testing.assert_allclose(blend.evaluate(1.0, wl), forward.evaluate(1.0, wl) / norm,
                               rtol=1e-3)
    np.testing.assert_allclose(blend.evaluate(-1.0, wl), backward.evaluate(-1.0, wl) / norm,
                               rtol=1e-3)
    theta = np.linspace(0.0, np.pi, 200_001)  # fine trapezoid of the tabulated interpolant
    total = 2 * np.pi * np.trapezoid(blend.evaluate(np.cos(theta), wl)
                                     * np.sin(theta)[:, None], theta, axis=0)
    np.testing.assert_allclose(total, 1.0, atol=1e-4)


def test_angle_blend_of_one_function_with_itself_is_that_function():
    angles = np.linspace(0.0, 180.0, 721)
    phase = DoubleHenyeyGreensteinPhase(0.67, 0.094, 0.743)
    blend = angle_blended_phase(phase, phase, angles, [550.0])
    nu = np.cos(np.deg2rad([0.0, 30.0, 90.0, 150.0]))
    np.testing.assert_allclose(blend.evaluate(nu, [550.0]), phase.evaluate(nu, [550.0]),
                               rtol=2e-3)


def test_tabulated_phase_repr_tells_apart_tables_that_differ_in_the_middle():
    # Cache fingerprints hash repr(phase); numpy elides the middle of long arrays in reprs.
    angles = np.linspace(0.0, 180.0, 2001)
    wl = np.linspace(360.0, 830.0, 48)
    values = henyey_greenstein(np.cos(np.deg2rad(angles)), 0.7)[:, None] * np.ones(48)
    changed = values.copy()
    changed[1000, 24] *= 1.01
    assert repr(TabulatedPhase(angles, values, wl)) != repr(TabulatedPhase(angles, changed, wl))
    assert repr(TabulatedPhase(angles, values, wl)) == repr(TabulatedPhase(angles, values, wl))
