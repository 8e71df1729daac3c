"""Control-chart constants against exact closed forms and the published tables."""

import math

import pytest

from station.analysis.constants import c4, chart_factors, d2, d3

# reference/standards.md §2.3: exact closed forms of E(R), a = arcsin(1/3).
ARCSIN_THIRD = math.asin(1 / 3)
EXACT_D2 = {
    2: 2 / math.sqrt(math.pi),
    3: 3 / math.sqrt(math.pi),
    4: (3 / math.sqrt(math.pi)) * (1 + 2 * ARCSIN_THIRD / math.pi),
    5: (5 / (2 * math.sqrt(math.pi))) * (1 + 6 * ARCSIN_THIRD / math.pi),
}

# standards.md §2.3, COMPUTED to 6 decimals: n: (d2, d3, c4, A2, A3, D3, D4, B3, B4).
SIX_DECIMALS = {
    2: (1.128379, 0.852502, 0.797885, 1.879971, 2.658681, 0, 3.266532, 0, 3.266532),
    3: (1.692569, 0.888368, 0.886227, 1.023327, 1.954410, 0, 2.574591, 0, 2.568170),
    4: (2.058751, 0.879808, 0.921318, 0.728597, 1.628103, 0, 2.282052, 0, 2.266047),
    5: (2.325929, 0.864082, 0.939986, 0.576819, 1.427299, 0, 2.114499, 0, 2.088998),
    6: (2.534413, 0.848040, 0.951533, 0.483246, 1.287128, 0, 2.003830, 0.030363, 1.969637),
    7: (2.704357, 0.833205, 0.959369, 0.419284, 1.181916, 0.075708, 1.924292, 0.117685, 1.882315),
    8: (2.847201, 0.819831, 0.965030, 0.372527, 1.099095, 0.136171, 1.863829, 0.185090, 1.814910),
    9: (2.970026, 0.807834, 0.969311, 0.336697, 1.031661, 0.184013, 1.815987, 0.239133, 1.760867),
    10: (3.077505, 0.797051, 0.972659, 0.308264, 0.975350, 0.223023, 1.776977, 0.283706, 1.716294),
}

# PUBLISHED 3-decimal table (AVEVA / VAX CSS, matches Montgomery):
# n: (A2, d2, D3, D4, A3, c4, B3, B4).
THREE_DECIMALS = {
    2: (1.880, 1.128, 0, 3.267, 2.659, 0.7979, 0, 3.267),
    3: (1.023, 1.693, 0, 2.574, 1.954, 0.8862, 0, 2.568),
    4: (0.729, 2.059, 0, 2.282, 1.628, 0.9213, 0, 2.266),
    5: (0.577, 2.326, 0, 2.114, 1.427, 0.9400, 0, 2.089),
    6: (0.483, 2.534, 0, 2.004, 1.287, 0.9515, 0.030, 1.970),
    7: (0.419, 2.704, 0.076, 1.924, 1.182, 0.9594, 0.118, 1.882),
    8: (0.373, 2.847, 0.136, 1.864, 1.099, 0.9650, 0.185, 1.815),
    9: (0.337, 2.970, 0.184, 1.816, 1.032, 0.9693, 0.239, 1.761),
    10: (0.308, 3.078, 0.223, 1.777, 0.975, 0.9727, 0.284, 1.716),
}
PUBLISHED_D3 = (0.853, 0.888, 0.880, 0.864, 0.848, 0.833, 0.820, 0.808, 0.797)
# qcc's se.R.unscaled (7 decimals, n = 2..10); printed to 7 decimals, good to about 1e-5.
QCC_D3 = (
    0.8525033,
    0.8883697,
    0.8798108,
    0.8640855,
    0.8480442,
    0.8332108,
    0.8198378,
    0.8078413,
    0.7970584,
)


@pytest.mark.parametrize("n", sorted(EXACT_D2))
def test_d2_matches_the_exact_closed_forms(n):
    assert d2(n) == pytest.approx(EXACT_D2[n], abs=1e-10)


def test_c4_matches_its_closed_forms():
    assert c4(2) == pytest.approx(math.sqrt(2 / math.pi), abs=1e-15)
    assert c4(3) == pytest.approx(math.sqrt(math.pi) / 2, abs=1e-15)
    assert c4(4) == pytest.approx(2 * math.sqrt(2 / (3 * math.pi)), abs=1e-15)
    # Large n (pooled degrees of freedom) must not overflow; c4 -> 1 - 1/(4n).
    assert c4(101) == pytest.approx(0.9975031640, abs=1e-10)
    # Exact values from Gamma(m)/Gamma(m - 1/2) in 60-digit decimal arithmetic.
    assert c4(10) == pytest.approx(0.97265927412158824336, abs=5e-15)
    assert c4(1000) == pytest.approx(0.99974978110151320321, abs=1e-13)
    assert c4(10000) == pytest.approx(0.99997499781235155757, abs=1e-15)
    assert c4(10**9) == pytest.approx(1 - 1 / (4 * 10**9), abs=1e-15)


def test_d3_of_two_has_its_closed_form():
    # Range of two normals is |X1 - X2| ~ sqrt(2)|Z|: variance 2 - 4/pi.
    assert d3(2) == pytest.approx(math.sqrt(2 - 4 / math.pi), abs=1e-10)


@pytest.mark.parametrize("n", sorted(SIX_DECIMALS))
def test_constants_match_the_six_decimal_table(n):
    f = chart_factors(n)
    ours = (f.d2, f.d3, f.c4, f.A2, f.A3, f.D3, f.D4, f.B3, f.B4)
    for name, mine, table in zip(
        ("d2", "d3", "c4", "A2", "A3", "D3", "D4", "B3", "B4"), ours, SIX_DECIMALS[n], strict=True
    ):
        assert mine == pytest.approx(table, abs=5.1e-7), f"{name}({n})"


@pytest.mark.parametrize("n", sorted(THREE_DECIMALS))
def test_constants_round_to_the_published_table(n):
    f = chart_factors(n)
    ours = (f.A2, f.d2, f.D3, f.D4, f.A3, f.c4, f.B3, f.B4)
    for name, mine, table in zip(
        ("A2", "d2", "D3", "D4", "A3", "c4", "B3", "B4"), ours, THREE_DECIMALS[n], strict=True
    ):
        # The published D4(3) = 2.574 comes from rounded d2 and d3 (exact: 2.574591), so allow
        # one unit in the last printed place rather than half of one.
        assert mine == pytest.approx(table, abs=1.0001e-3), f"{name}({n})"
    assert f.d3 == pytest.approx(PUBLISHED_D3[n - 2], abs=5.1e-4)
    assert f.d3 == pytest.approx(QCC_D3[n - 2], abs=1e-5)


def test_individuals_factors_use_the_moving_range_of_two():
    f = chart_factors(1)
    assert f.n == 1
    # The published 2.660 is 3/1.128, from the rounded d2(2); exactly it is 2.65868.
    assert math.isclose(f.E2, 2.660, abs_tol=1.5e-3)
    assert math.isclose(f.E2, 3 * math.sqrt(math.pi) / 2, abs_tol=1e-10)
    assert math.isclose(f.D4, 3.267, abs_tol=5e-4)
    assert f.D3 == 0
    assert f.d2 == d2(2) and f.A2 == f.E2


def test_factors_are_derived_from_d2_d3_c4():
    for n in (2, 5, 11, 25):
        f = chart_factors(n)
        assert math.isclose(f.A2, 3 / (f.d2 * math.sqrt(n)), rel_tol=1e-12)
        assert math.isclose(f.A3, 3 / (f.c4 * math.sqrt(n)), rel_tol=1e-12)
        assert math.isclose(f.D4, 1 + 3 * f.d3 / f.d2, rel_tol=1e-12)
        assert math.isclose(f.B4, 1 + 3 * math.sqrt(1 - f.c4**2) / f.c4, rel_tol=1e-12)
        assert math.isclose(f.E2, 3 / f.d2, rel_tol=1e-12)


def test_d2_grows_like_the_expected_range_for_large_subgroups():
    # Published d2(25) = 3.931 (qcc table); monotone in n.
    assert d2(25) == pytest.approx(3.931, abs=5e-4)
    assert all(d2(n) < d2(n + 1) for n in range(2, 30))


@pytest.mark.parametrize("bad", [0, -1, 1.5, True])
def test_sizes_below_two_or_fractional_are_refused(bad):
    with pytest.raises(ValueError):
        d2(bad)
    with pytest.raises(ValueError):
        c4(bad)
