"""Kitchens generated from a seed (``teachbot world generate``): the distributions they are drawn from
(``data/generator/kitchens.toml``, :mod:`.distributions`), the drawing (:mod:`.layout`, :mod:`.rooms`) and the
written kitchen file (:mod:`.writer`)."""

from bullet_world.generation.distributions import DEFAULT_DISTRIBUTIONS, Distributions, load_distributions
from bullet_world.generation.writer import cached_kitchens, generate_kitchen, generate_kitchens

__all__ = ["DEFAULT_DISTRIBUTIONS", "Distributions", "cached_kitchens", "generate_kitchen", "generate_kitchens",
           "load_distributions"]
