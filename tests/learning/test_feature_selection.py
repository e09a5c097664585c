"""Feature selection of thesis chapter 5: information gain (FI), CFS merit, ES and ER."""

import importlib.util
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from learning.features.selection import (
    SELECTION_METHODS,
    backward_elimination,
    cfs_merit,
    chance_corrected_information_gain,
    computational_subsets,
    default_bin_count,
    discretize,
    filter_information_gain,
    forward_selection,
    information_gain,
    merit_from_correlations,
    select_features,
    symmetrical_uncertainty,
)

INFORMATIVE = [0, 1, 2]
COPIES = {3: 0, 4: 1, 5: 2, 6: 1}  # copy -> original


def redundant_problem(n_samples, seed, n_features=40):
    """Four classes; 0, 1, 2 informative and pairwise independent; 3-6 copies; the rest noise."""
    rng = np.random.default_rng(seed)
    y = rng.permutation(np.arange(n_samples) % 4)
    X = rng.normal(size=(n_samples, n_features))
    high_half, odd = y >= 2, y % 2 == 1
    X[:, 0] = 3.0 * high_half + 0.5 * rng.normal(size=n_samples)
    X[:, 1] = 3.0 * odd + 0.5 * rng.normal(size=n_samples)
    X[:, 2] = 3.0 * (high_half ^ odd) + 0.5 * rng.normal(size=n_samples)
    X[:, 3] = X[:, 0]  # exact copy
    X[:, 4] = X[:, 1]  # exact copy
    X[:, 5] = X[:, 2] + 1e-9 * rng.normal(size=n_samples)  # near copy, same ranks
    X[:, 6] = 5.0 - 2.0 * X[:, 1]  # decreasing affine copy
    return X, y


def ordered_problem(n_samples, seed, n_features=40, separation=5.0):
    """Four classes whose means differ along features 0, 1, 2 (in different orders); the rest noise."""
    rng = np.random.default_rng(seed)
    y = rng.permutation(np.arange(n_samples) % 4)
    X = rng.normal(size=(n_samples, n_features))
    for feature, order in enumerate(([0, 1, 2, 3], [1, 3, 0, 2], [3, 0, 2, 1])):
        X[:, feature] = separation * np.array(order)[y] + rng.normal(size=n_samples)
    return X, y


# ------------------------------------------------------------ discretisation


def test_default_bin_count_grows_with_the_cube_root():
    assert [default_bin_count(n) for n in (1, 2, 8, 12, 27, 100, 10**6)] == [2, 2, 2, 3, 3, 5, 10]


def test_discretize_makes_equal_frequency_bins_and_keeps_ties_together():
    codes = discretize(np.arange(12.0)[:, None])
    assert codes[:, 0].tolist() == [0] * 4 + [1] * 4 + [2] * 4
    tied = np.array([1, 1, 1, 1, 1, 1, 2, 3, 4, 5, 6, 7], dtype=float)[:, None]
    tied_codes = discretize(tied)[:, 0]
    assert len(set(tied_codes[:6])) == 1  # equal values share a bin
    assert np.all(np.diff(tied_codes) >= 0)  # order is preserved
    flags = np.array([[0.0], [1.0], [1.0], [0.0], [1.0]])
    assert discretize(flags, n_bins=2)[:, 0].tolist() == [0, 1, 1, 0, 1]


# ----------------------------------------------------------- information gain


def test_information_gain_matches_a_hand_computation():
    y = np.array([0, 0, 1, 1])
    X = np.column_stack([y, [0, 0, 0, 1], [7, 7, 7, 7]]).astype(float)
    # H(Y) = 1; f = [0,0,0,1]: H(Y|f) = 3/4 * H(1/3, 2/3) = 3/4 * (log2 3 - 2/3).
    expected = [1.0, 1.0 - 0.75 * (math.log2(3) - 2 / 3), 0.0]
    np.testing.assert_allclose(information_gain(X, y), expected, atol=1e-12)


def test_information_gain_for_multiclass_string_labels():
    X = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 2.0], [1.0, 3.0]])
    # Column 0 halves four equiprobable classes: 2 - 1 = 1 bit; column 1 names them: 2 bits.
    np.testing.assert_allclose(information_gain(X, ["a", "b", "c", "d"], n_bins=4), [1.0, 2.0], atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(
    st.lists(st.integers(-20, 20), min_size=2, max_size=30).flatmap(
        lambda values: st.tuples(
            st.just(values), st.lists(st.integers(0, 3), min_size=len(values), max_size=len(values))
        )
    )
)
def test_information_gain_is_bounded_and_invariant_to_increasing_maps(data):
    values, labels = data
    column = np.array(values, dtype=float)[:, None]
    gain = information_gain(column, labels)[0]
    _, counts = np.unique(labels, return_counts=True)
    class_entropy = -np.sum(counts / len(labels) * np.log2(counts / len(labels)))
    assert -1e-12 <= gain <= class_entropy + 1e-9
    assert information_gain(4.0 * column + 3.0, labels)[0] == pytest.approx(gain, abs=1e-12)


def test_plug_in_gain_is_positive_for_almost_all_noise_at_n_12():
    """Why FI needs a chance correction: eq. 5.1 with tau = 0 would keep most noise."""
    rng = np.random.default_rng(0)
    noise = rng.normal(size=(12, 200))
    assert np.mean(information_gain(noise, np.arange(12) % 4) > 0) > 0.9


@pytest.mark.parametrize("n_samples", [12, 100])
def test_filter_keeps_informative_and_drops_most_noise(n_samples):
    kept_noise, noise_total = 0, 0
    for seed in range(10):
        X, y = ordered_problem(n_samples, seed)
        kept = filter_information_gain(X, y)
        assert set(INFORMATIVE) <= set(kept.tolist()), f"seed {seed}: {kept}"
        kept_noise += np.sum(kept >= 3)
        noise_total += X.shape[1] - 3
    assert kept_noise / noise_total < 0.12


def test_filter_keeps_redundant_copies_but_not_noise_at_n_100():
    X, y = redundant_problem(100, seed=1)
    kept = set(filter_information_gain(X, y).tolist())
    assert set(range(7)) <= kept
    assert len(kept - set(range(7))) <= 4


def test_chance_correction_is_stricter_at_a_smaller_significance():
    X, y = ordered_problem(12, seed=3)
    loose = chance_corrected_information_gain(X, y, significance=0.2)
    strict = chance_corrected_information_gain(X, y, significance=0.001)
    assert np.all(strict[3:] <= loose[3:]) and np.any(strict < loose)
    assert np.all(information_gain(X, y) >= loose)


# --------------------------------------------------------------- CFS merit


def test_merit_formula_matches_a_hand_computation_with_m_times_m_minus_1():
    class_correlations = [0.8, 0.4, 0.6]
    feature_correlations = [[1.0, 0.2, 0.5], [0.2, 1.0, 0.1], [0.5, 0.1, 1.0]]
    # m = 3, mean r_cf = 0.6, mean r_ff = 0.8 / 3: 3 * 0.6 / sqrt(3 + 3 * 2 * 0.8 / 3) = 1.8 / sqrt(4.6).
    merit = merit_from_correlations(class_correlations, feature_correlations)
    assert merit == pytest.approx(1.8 / math.sqrt(4.6))
    assert merit != pytest.approx(1.8 / math.sqrt(3 + 3 * 4 * 0.8 / 3))  # the thesis's misprint m(m+1)
    assert merit_from_correlations([0.7], [[1.0]]) == pytest.approx(0.7)


def test_symmetrical_uncertainty_matches_a_hand_computation():
    y = np.array([0, 0, 1, 1])
    X = np.column_stack([y, [0, 0, 0, 1]]).astype(float)
    _, feature_su = symmetrical_uncertainty(X, y)
    bias = 1.0 / (2 * 4 * math.log(2))  # Miller-Madow (K - 1) / (2 n ln 2) per extra cell
    h_a, h_b, h_ab = 1.0 + bias, (2 - 0.75 * math.log2(3)) + bias, 1.5 + 2 * bias
    assert feature_su[0, 1] == pytest.approx(2 * (h_a + h_b - h_ab) / (h_a + h_b))
    assert feature_su[0, 0] == 1.0


def test_cfs_merit_uses_the_same_correlations_as_the_search():
    X, y = redundant_problem(100, seed=2)
    class_su, feature_su = symmetrical_uncertainty(X, y)
    subset = [0, 2, 9, 3]
    expected = merit_from_correlations(class_su[subset], feature_su[np.ix_(subset, subset)])
    assert cfs_merit(X, y, subset) == pytest.approx(expected)
    assert feature_su[0, 3] == pytest.approx(1.0) and feature_su[1, 6] == pytest.approx(1.0)
    assert class_su[9] == 0.0  # a noise feature that fails the chance test


# ---------------------------------------------------------------- ES and ER


@pytest.mark.parametrize("selector", [forward_selection, backward_elimination])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_search_recovers_informative_and_drops_copies(selector, seed):
    X, y = redundant_problem(100, seed)
    assert selector(X, y).tolist() == INFORMATIVE


@pytest.mark.parametrize("selector", [forward_selection, backward_elimination])
def test_search_keeps_the_lower_index_of_a_copy_placed_first(selector):
    X, y = redundant_problem(100, seed=0)
    swapped = X[:, [3, 1, 2, 0] + list(range(4, X.shape[1]))]  # the copy of feature 0 now sits at 0
    assert selector(swapped, y).tolist() == INFORMATIVE


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_search_handles_twelve_samples(seed):
    X, y = ordered_problem(12, seed)
    for selector in (forward_selection, backward_elimination):
        chosen = selector(X, y)
        assert 0 < chosen.size <= 6 and set(chosen.tolist()) & set(INFORMATIVE)


def test_forward_selection_is_locally_optimal_and_respects_max_features():
    X, y = redundant_problem(60, seed=4, n_features=20)
    chosen = forward_selection(X, y).tolist()
    merit = cfs_merit(X, y, chosen)
    for extra in set(range(20)) - set(chosen):
        assert cfs_merit(X, y, chosen + [extra]) <= merit + 1e-9
    class_su, _ = symmetrical_uncertainty(X, y)
    assert forward_selection(X, y, max_features=1).tolist() == [int(np.argmax(class_su))]


def test_backward_elimination_is_locally_optimal():
    X, y = ordered_problem(24, seed=5, n_features=15)
    chosen = backward_elimination(X, y).tolist()
    merit = cfs_merit(X, y, chosen)
    for dropped in chosen if len(chosen) > 1 else []:
        assert cfs_merit(X, y, [f for f in chosen if f != dropped]) < merit


@settings(max_examples=25, deadline=None)
@given(
    st.integers(1, 25).flatmap(
        lambda n: st.tuples(
            st.lists(st.lists(st.integers(-3, 3), min_size=6, max_size=6), min_size=n, max_size=n),
            st.lists(st.integers(0, 2), min_size=n, max_size=n),
        )
    ),
    st.sampled_from(SELECTION_METHODS),
)
def test_every_method_returns_sorted_distinct_in_range_nonempty_indices(data, method):
    rows, labels = data
    X = np.array(rows, dtype=float)
    chosen = select_features(X, labels, method)
    assert chosen.size > 0 and np.all(np.diff(chosen) > 0)
    assert chosen.min() >= 0 and chosen.max() < X.shape[1]
    assert np.array_equal(select_features(3.0 * X - 1.0, labels, method), chosen)  # rank-based, deterministic


# ---------------------------------------------------------------- front door


def test_select_features_dispatches_and_accepts_any_case():
    X, y = redundant_problem(100, seed=0)
    assert select_features(X, y, "none").tolist() == list(range(X.shape[1]))
    assert np.array_equal(select_features(X, y, "FI"), filter_information_gain(X, y))
    assert select_features(X, y, "es").tolist() == INFORMATIVE
    assert select_features(X, y, " ER ").tolist() == INFORMATIVE


def test_unknown_method_names_the_accepted_ones():
    X, y = redundant_problem(20, seed=0)
    with pytest.raises(ValueError, match="'none', 'FI', 'ES', 'ER'"):
        select_features(X, y, "wrapper")
    with pytest.raises(ValueError, match="accepted"):
        computational_subsets(X, y, [0], method=None)


def test_computational_subsets_one_vs_rest_for_four_concepts():
    rng = np.random.default_rng(7)
    names = np.array(["fruit", "snack", "can", "drink"])
    codes = rng.permutation(np.arange(60) % 4)
    X = rng.normal(size=(60, 30))
    for concept in range(4):
        X[:, concept] = 4.0 * (codes == concept) + 0.5 * rng.normal(size=60)
    concepts = [*names.tolist(), "cutlery"]
    for method in ("ES", "ER", "FI"):
        subsets = computational_subsets(X, names[codes], concepts, method=method)
        assert list(subsets) == concepts
        for index, concept in enumerate(names):
            assert index in subsets[concept] and np.sum(subsets[concept] >= 4) <= 3, (method, concept)
        assert subsets["cutlery"].tolist() == list(range(30))  # no positive example yet
    by_integer = computational_subsets(X, codes.tolist(), [0, 1, 2, 3])
    assert all(
        np.array_equal(by_integer[k], computational_subsets(X, names[codes], [names[k]])[names[k]]) for k in range(4)
    )


def test_concept_with_only_positive_examples_gets_all_features():
    X, _ = redundant_problem(12, seed=0)
    assert computational_subsets(X, ["fruit"] * 12, ["fruit"])["fruit"].tolist() == list(range(40))


# ---------------------------------------------------------------- edge cases


def test_single_class_has_no_gain_and_searches_fall_back_to_all_features():
    X, _ = redundant_problem(30, seed=0, n_features=8)
    y = np.zeros(30, dtype=int)
    assert np.all(information_gain(X, y) == 0.0)
    assert filter_information_gain(X, y).size == 0
    for method in SELECTION_METHODS:
        assert select_features(X, y, method).tolist() == list(range(8))


def test_constant_feature_has_zero_gain_and_is_never_selected():
    X, y = redundant_problem(100, seed=0, n_features=10)
    X[:, 2] = 1.5
    assert information_gain(X, y)[2] == 0.0
    class_su, feature_su = symmetrical_uncertainty(X, y)
    assert class_su[2] == 0.0 and np.all(feature_su[2] == 0.0)
    for method in ("FI", "ES", "ER"):
        assert 2 not in select_features(X, y, method)


def test_two_samples():
    X = np.array([[0.0, 5.0, 1.0], [1.0, 5.0, -1.0]])
    np.testing.assert_allclose(information_gain(X, [0, 1]), [1.0, 0.0, 1.0])
    for method in SELECTION_METHODS:  # nothing is significant with two samples: keep all
        assert select_features(X, [0, 1], method).tolist() == [0, 1, 2]


# ---------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("X", "y", "message"),
    [
        (np.zeros(5), [0] * 5, "2-D"),
        (np.zeros((2, 2, 2)), [0, 1], "2-D"),
        (np.zeros((0, 3)), [], "at least one sample"),
        ([["a", "b"], ["c", "d"]], [0, 1], "numbers"),
        ([[1.0, 2.0], [3.0]], [0, 1], "rectangular"),
        ([[1.0, np.nan], [3.0, 4.0]], [0, 1], "NaN"),
        (np.zeros((3, 2)), [0, 1], "3 rows"),
        (np.zeros((2, 2)), [[0], [1]], "1-D"),
        (np.zeros((2, 2)), [0.5, 1.0], "non-integer"),
        (np.zeros((2, 2)), np.array([1, "a", None], dtype=object)[[0, 2]], "cannot be compared"),
    ],
)
def test_bad_inputs_are_explained(X, y, message):
    with pytest.raises(ValueError, match=message):
        information_gain(X, y)


def test_bad_parameters_are_explained():
    X, y = redundant_problem(12, seed=0, n_features=8)
    with pytest.raises(ValueError, match="n_bins must be None or an integer >= 2"):
        information_gain(X, y, n_bins=1)
    with pytest.raises(ValueError, match="significance must be a number strictly between 0 and 1"):
        filter_information_gain(X, y, significance=1.5)
    with pytest.raises(ValueError, match="max_features must be None or an integer >= 1"):
        forward_selection(X, y, max_features=0)
    with pytest.raises(ValueError, match=r"distinct indices in \[0, 7\]"):
        cfs_merit(X, y, [0, 8])
    with pytest.raises(ValueError, match="distinct"):
        cfs_merit(X, y, [1, 1])
    with pytest.raises(ValueError, match="non-empty 1-D sequence of integer"):
        cfs_merit(X, y, [])
    with pytest.raises(ValueError, match="labels has 3 entries but X has 12 rows"):
        computational_subsets(X, ["a", "b", "c"], ["a"])
    with pytest.raises(ValueError, match=r"shape \(m,\)"):
        merit_from_correlations([0.5, 0.5], [[1.0]])


def test_module_imports_no_simulator_viewer_or_application_code():
    path = Path(__file__).resolve().parents[2] / "learning" / "features" / "selection.py"
    script = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('feature_selection', {str(path)!r})\n"
        "spec.loader.exec_module(importlib.util.module_from_spec(spec))\n"
        "banned = ('pybullet', 'cv2', 'meshcat', 'torch', 'bullet_world', 'robot', 'dialog')\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in banned))\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True)
    assert result.stdout.strip() == "[]"
    assert importlib.util.find_spec("learning.features.selection") is not None


# ---------------------------------------------------------------- speed-ups keep the results


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 10_000), st.sampled_from([0.05, 0.5]))
def test_forward_search_on_rows_on_demand_equals_the_full_matrix_search(seed, significance):
    from learning.features.selection import LazyCorrelations, _forward, _representatives, prepare

    rng = np.random.default_rng(seed)
    n_samples, n_features = int(rng.integers(5, 120)), int(rng.integers(2, 30))
    y = rng.integers(0, int(rng.integers(2, 5)), n_samples)
    X = rng.normal(size=(n_samples, n_features))
    X[:, : min(3, n_features)] += rng.normal(0, 2, (5, min(3, n_features)))[y]
    if n_features > 4:
        X[:, -1], X[:, -2] = X[:, 0], 5.0 - 2.0 * X[:, 1]  # exact and decreasing copies
    if seed % 3 == 0:
        X = np.round(X)  # ties and few distinct values
    table, codes = prepare(X, y, None)
    class_su = table.class_su(codes, significance)
    lazy = _forward(class_su, LazyCorrelations(table), None)
    assert np.array_equal(lazy, _forward(class_su, table.feature_su, None))
    relevant = np.flatnonzero(class_su > 0)
    assert np.array_equal(LazyCorrelations(table).representatives(relevant),
                          _representatives(table.feature_su[np.ix_(relevant, relevant)]))


def test_joint_entropies_from_the_count_lookup_equal_the_per_cell_formula_bit_for_bit():
    """The -p log2 p lookup by count (issue 28) must give the very bits of computing every cell's term."""
    from learning.features.information import DiscreteFeatures, _joint_entropies

    for seed, n in enumerate((1, 2, 7, 150, 500)):
        rng = np.random.default_rng(seed)
        table = DiscreteFeatures(np.round(rng.normal(size=(n, 12)), 1), None)
        block = table.one_hot[:, table.starts[3] : table.starts[3] + table.levels[3]]
        counts = (block.T.astype(np.float32) @ table.one_hot32).astype(np.float64)
        probabilities = counts / n
        terms = -(probabilities * np.log2(np.where(probabilities > 0, probabilities, 1.0))).sum(axis=0)
        joint, cells = _joint_entropies(block, table.one_hot32, table.starts)
        np.testing.assert_array_equal(joint, np.add.reduceat(terms, table.starts))
        np.testing.assert_array_equal(cells, np.add.reduceat((counts > 0).sum(axis=0), table.starts))


def test_the_chi2_quantile_is_scipy_stats_own_to_the_bit():
    """information.py computes chi2.ppf without importing scipy.stats (start-up time); the numbers must not move."""
    from scipy.stats import chi2

    from learning.features.information import _chi2_quantile

    for probability in (0.5, 0.9, 0.95, 0.99, 0.999, 0.123):
        for degrees in range(1, 120):
            assert _chi2_quantile(probability, degrees) == float(chi2.ppf(probability, degrees))
