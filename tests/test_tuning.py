"""Physical tuning [3.26]–[3.35] and per-term budgets [4.11]–[4.12]."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shoal.engine.pso import tuning


def test_figure_3_3_worked_example():
    t = tuning.from_coefficients(omega=0.6, c_hat=4.0, dt=1.0, d=1)
    assert (t.U_j, t.A_plus_j, t.A_minus_j) == pytest.approx((10.0, 4.0, 8.0))


@pytest.mark.parametrize(
    "dt, U, A_plus, beta, omega, c_hat",
    [(1.0, 20.0, 20.0, 1.0, 0.0, 20.0), (1.0, 20.0, 4.0, 0.2, 0.8, 4.0), (0.2, 20.0, 20.0, 0.2, 0.8, 4.0),
     (0.2, 20.0, 100.0, 1.0, 0.0, 20.0)],
)
def test_section_3_5_cases(dt, U, A_plus, beta, omega, c_hat):
    t = tuning.from_limits(dt, U, A_plus=A_plus, d=1)
    assert (t.beta, t.omega, t.c_hat) == pytest.approx((beta, omega, c_hat))
    assert t.A_minus == pytest.approx(2 * A_plus)


def test_two_dimensions_scale_by_root_d():
    t = tuning.from_limits(0.1, 3.0, A_plus=15.0, d=2)
    assert t.c_hat == pytest.approx(15.0 * 0.1 / math.sqrt(2))  # [3.32]
    assert t.U_j == pytest.approx(3.0 / math.sqrt(2))


def test_a_minus_gives_same_tuning_as_a_plus():
    a = tuning.from_limits(0.5, 4.0, A_plus=3.0, d=2)
    b = tuning.from_limits(0.5, 4.0, A_minus=6.0, d=2)
    assert a == b


def test_beta_above_one_is_refused_with_reason():
    with pytest.raises(tuning.TuningError, match="must be faster"):
        tuning.from_limits(1.0, 2.0, A_plus=5.0)


@pytest.mark.parametrize("bad", [dict(dt=0.0), dict(U=-1.0), dict(A_plus=float("nan"))])
def test_non_positive_inputs_are_refused(bad):
    args = dict(dt=1.0, U=2.0, A_plus=1.0) | bad
    with pytest.raises(tuning.TuningError):
        tuning.from_limits(args["dt"], args["U"], A_plus=args["A_plus"])


def test_exactly_one_acceleration_limit():
    with pytest.raises(tuning.TuningError, match="exactly one"):
        tuning.from_limits(1.0, 2.0, A_plus=1.0, A_minus=2.0)


def test_inverse_refuses_omega_outside_robot_subset():
    with pytest.raises(tuning.TuningError, match="omega"):
        tuning.from_coefficients(1.0, 1.0, 0.1)


@given(
    dt=st.floats(1e-3, 5.0), U=st.floats(1e-2, 100.0), beta=st.floats(1e-3, 1.0), d=st.integers(1, 3)
)
def test_round_trip_limits_coefficients(dt, U, beta, d):
    t = tuning.from_beta(dt, U, beta, d)
    back = tuning.from_coefficients(t.omega, t.c_hat, dt, d)
    assert back.U == pytest.approx(U, rel=1e-9)
    assert back.A_plus == pytest.approx(t.A_plus, rel=1e-9)
    assert back.beta == pytest.approx(beta, rel=1e-9, abs=1e-12)


def test_split_and_term_budget():
    assert tuning.split(4.0, 0.25) == pytest.approx((1.0, 3.0))
    with pytest.raises(tuning.TuningError):
        tuning.split(4.0, 1.5)
    U_n, A_n = tuning.term_budget(1.0, beta=0.5, dt=0.1, d=2)
    assert A_n == pytest.approx(math.sqrt(2) / 0.1)  # [4.11]
    assert U_n == pytest.approx(math.sqrt(2) / 0.5)  # [4.12]
