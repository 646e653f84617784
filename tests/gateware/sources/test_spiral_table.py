import math

import pytest
from hypothesis import given, settings, strategies as st

from galvoscan.gateware.sources.spiral_table import SpiralTable


def test_paper_default_shape():
    table = SpiralTable()
    assert (table.points, table.sampling) == (128, "gaussian")
    assert len(table.x) == len(table.y) == 128
    # One sine period: centre, +edge a quarter in, centre, -edge.
    assert table.x[0] == 0 and table.x[32] == 32767 and table.x[64] == 0 and table.x[96] == -32767
    # Y is X a quarter period on (the cosine).
    assert table.y == table.x[32:] + table.x[:32]


def test_uniform_is_the_sine():
    # Written independently: equal phase steps of a sine, full scale 32767.
    table = SpiralTable(sampling="uniform")
    assert table.x == [round(32767 * math.sin(2 * math.pi * i / 128)) for i in range(128)]
    assert table.y == [round(32767 * math.cos(2 * math.pi * i / 128)) for i in range(128)]


@pytest.mark.parametrize("sigma", [0.3, 0.8, 2.0])
def test_gaussian_spacing_follows_the_truncated_normal(sigma):
    """Within a quarter, equal steps in time are equal steps in probability of |N(0, σ)|
    truncated to the half-swing: checked with math.erf, not with the table's own code."""
    table = SpiralTable(sampling="gaussian", sigma=sigma)

    def cdf(a):     # P(|X| <= a | |X| <= 1), X ~ N(0, σ)
        return math.erf(a / (sigma * math.sqrt(2))) / math.erf(1 / (sigma * math.sqrt(2)))

    for k in range(33):
        assert cdf(table.x[k] / 32767) == pytest.approx(k / 32, abs=2e-4)


def test_gaussian_puts_more_points_near_the_centre():
    """The paper's point: sampled like a Gaussian, more of the angles lie near the middle of
    the swing than sampled uniformly in phase."""
    def near_centre(table):
        return sum(abs(v) < 32767 / 3 for v in table.x)

    gaussian = near_centre(SpiralTable(sampling="gaussian", sigma=0.8))
    uniform = near_centre(SpiralTable(sampling="uniform"))
    assert gaussian > 1.5 * uniform
    # And step sizes grow from the centre to the edge (uniform: they shrink).
    steps = [b - a for a, b in zip(SpiralTable().x[:33], SpiralTable().x[1:33])]
    assert steps == sorted(steps)


def test_deterministic():
    assert SpiralTable(sigma=0.7).x == SpiralTable(sigma=0.7).x


@pytest.mark.parametrize("kwargs, message", [
    ({"points": 130}, "multiple of 4"),
    ({"points": 4}, "multiple of 4 from 8"),
    ({"points": 8192}, "to 4096"),
    ({"points": 128.0}, "multiple of 4"),
    ({"points": True}, "multiple of 4"),
    ({"sampling": "cosine"}, "sampling must be one of"),
    ({"sigma": 0}, "sigma must be"),
    ({"sigma": -1}, "sigma must be"),
    ({"sigma": float("nan")}, "sigma must be"),
    ({"sigma": float("inf")}, "sigma must be"),
    ({"sigma": "1"}, "sigma must be"),
])
def test_bad_parameters(kwargs, message):
    with pytest.raises(ValueError, match=message):
        SpiralTable(**kwargs)


@settings(max_examples=60, deadline=None)
@given(points=st.integers(2, 1024).map(lambda n: 4 * n),
       sampling=st.sampled_from(["gaussian", "uniform"]),
       sigma=st.floats(0.05, 100))
def test_any_valid_table_is_in_range_and_symmetric(points, sampling, sigma):
    table = SpiralTable(points=points, sampling=sampling, sigma=sigma)
    half, quarter = points // 2, points // 4
    for values in (table.x, table.y):
        assert all(-32767 <= v <= 32767 for v in values)
    # Odd symmetry over half a period, and the edges are reached exactly.
    assert all(table.x[i + half] == -table.x[i] for i in range(half))
    assert table.x[quarter] == 32767 and table.x[0] == 0
    # Rising through the first quarter.
    assert table.x[:quarter + 1] == sorted(table.x[:quarter + 1])
