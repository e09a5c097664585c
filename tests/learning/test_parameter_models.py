"""ParameterModel: GMM hypotheses k = 1..m, BIC choice, noise prior (thesis §4.2.3)."""

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from learning.recipes.parameter_models import ParameterModel

STOVE = np.array([0.5, 0.4, 0.9])
CUPBOARD = np.array([0.5, -0.5, 1.2])


def unimodal_locations(n, seed):
    return np.random.default_rng(seed).normal(STOVE, 0.03, size=(n, 3))


def bimodal_locations(n, seed):
    rng = np.random.default_rng(seed)
    first = rng.normal(STOVE, 0.03, size=(n // 2, 3))
    second = rng.normal(CUPBOARD, 0.03, size=(n - n // 2, 3))
    return np.vstack([first, second])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bic_picks_one_component_on_unimodal_data(seed):
    model = ParameterModel(0.02, rng=np.random.default_rng(seed)).fit(unimodal_locations(16, seed))
    assert model.n_components_ == 1
    assert sorted(model.bic_per_k_) == list(range(1, 17))
    assert min(model.bic_per_k_, key=model.bic_per_k_.get) == 1


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bic_picks_two_components_on_clearly_bimodal_data(seed):
    model = ParameterModel(0.02, rng=np.random.default_rng(seed)).fit(bimodal_locations(16, seed))
    assert model.n_components_ == 2
    closest_means = sorted(np.linalg.norm(model.means_ - centre, axis=1).min() for centre in (STOVE, CUPBOARD))
    assert closest_means[-1] < 0.05
    np.testing.assert_allclose(model.weights_, [0.5, 0.5], atol=0.01)


def test_single_demonstration_uses_the_noise_prior_as_covariance():
    noise = np.array([0.02, 0.02, 0.05])
    model = ParameterModel(noise).fit(STOVE[None, :])
    assert model.n_components_ == 1
    assert model.bic_per_k_.keys() == {1}
    np.testing.assert_allclose(model.covariances_[0], np.diag(noise**2))
    np.testing.assert_allclose(model.means_[0], STOVE)
    # three noise standard deviations along any single axis is distance 3
    offsets = np.array([[3 * 0.02, 0, 0], [0, -3 * 0.02, 0], [0, 0, 3 * 0.05]])
    np.testing.assert_allclose(model.mahalanobis(STOVE + offsets), [3.0, 3.0, 3.0])
    expected = multivariate_normal(STOVE, np.diag(noise**2)).logpdf(STOVE + offsets)
    np.testing.assert_allclose(model.log_likelihood(STOVE + offsets), expected)


def test_noise_floor_is_added_to_the_sample_covariance():
    samples = unimodal_locations(10, 3)
    model = ParameterModel(0.02).fit(samples)
    expected = np.cov(samples.T, bias=True) + np.eye(3) * 0.02**2
    np.testing.assert_allclose(model.covariances_[0], expected)


def test_mahalanobis_gate_accepts_near_and_rejects_far_points():
    model = ParameterModel(0.02, rng=np.random.default_rng(5)).fit(unimodal_locations(8, 5))
    near, far = STOVE + [0.01, -0.01, 0.0], STOVE + [0.3, 0.0, 0.0]
    distances = model.mahalanobis(np.vstack([near, far]))
    assert distances[0] < 3.0 < distances[1]
    assert model.log_likelihood(near)[0] > model.log_likelihood(far)[0]


def test_mahalanobis_is_the_distance_to_the_nearest_component():
    model = ParameterModel(0.02, rng=np.random.default_rng(0)).fit(bimodal_locations(16, 0))
    assert model.n_components_ == 2
    assert model.mahalanobis(CUPBOARD)[0] < 3.0
    assert model.mahalanobis(STOVE)[0] < 3.0
    assert model.mahalanobis((STOVE + CUPBOARD) / 2)[0] > 3.0


def test_log_likelihood_matches_the_mixture_density():
    model = ParameterModel(0.02, rng=np.random.default_rng(0)).fit(bimodal_locations(16, 0))
    points = np.vstack([STOVE, CUPBOARD, STOVE + 0.05])
    density = sum(
        weight * multivariate_normal(mean, covariance).pdf(points)
        for weight, mean, covariance in zip(model.weights_, model.means_, model.covariances_)
    )
    np.testing.assert_allclose(model.log_likelihood(points), np.log(density))


def test_same_generator_seed_gives_the_same_model():
    data = bimodal_locations(12, 4)
    first = ParameterModel(0.02, rng=np.random.default_rng(9)).fit(data)
    second = ParameterModel(0.02, rng=np.random.default_rng(9)).fit(data)
    np.testing.assert_array_equal(first.means_, second.means_)
    assert first.bic_per_k_ == second.bic_per_k_


def test_hypotheses_are_capped_by_demonstrations_and_max_components():
    data = bimodal_locations(12, 1)
    assert ParameterModel(0.02).fit(data, n_demonstrations=3).bic_per_k_.keys() == {1, 2, 3}
    assert ParameterModel(0.02, max_components=2).fit(data).bic_per_k_.keys() == {1, 2}
    repeated = np.repeat(STOVE[None, :], 5, axis=0)
    assert ParameterModel(0.02).fit(repeated).bic_per_k_.keys() == {1}


def test_add_counts_one_demonstration_per_call_and_refits():
    model = ParameterModel(0.02, rng=np.random.default_rng(0))
    model.add(STOVE)
    assert model.n_demonstrations_ == 1 and model.n_components_ == 1
    model.add(np.vstack([CUPBOARD, CUPBOARD + 0.01]))
    assert model.n_demonstrations_ == 2
    assert model.samples_.shape == (3, 3)
    assert model.bic_per_k_.keys() == {1, 2}
    assert model.n_components_ == 2
    with pytest.raises(ValueError, match="2 features"):
        model.add([0.1, 0.2])


@pytest.mark.parametrize(
    ("noise", "samples", "message"),
    [
        (-0.1, [[0.0, 0.0]], "noise_std must be a positive"),
        (0.1, [0.0, 1.0], "2-D array"),
        (0.1, [[0.0, np.nan]], "NaN or infinite"),
        ([0.1, 0.1, 0.1], [[0.0, 1.0]], "2 features but noise_std has 3"),
    ],
)
def test_bad_input_names_the_problem(noise, samples, message):
    with pytest.raises(ValueError, match=message):
        ParameterModel(noise).fit(np.array(samples, dtype=float))


def test_unfitted_model_and_wrong_point_size_are_reported():
    with pytest.raises(ValueError, match="no data yet"):
        ParameterModel(0.02).mahalanobis(STOVE)
    model = ParameterModel(0.02).fit(STOVE[None, :])
    with pytest.raises(ValueError, match="3 features per row"):
        model.mahalanobis([0.1, 0.2])
    with pytest.raises(ValueError, match="Generator"):
        ParameterModel(0.02, rng=42)


def test_heaviest_component_mean_follows_the_larger_cluster():
    rng = np.random.default_rng(8)
    data = np.vstack([rng.normal(CUPBOARD, 0.03, (4, 3)), rng.normal(STOVE, 0.03, (12, 3))])
    model = ParameterModel(0.02, rng=np.random.default_rng(1)).fit(data)
    assert model.n_components_ == 2
    assert np.linalg.norm(model.heaviest_component_mean() - STOVE) < 0.03
