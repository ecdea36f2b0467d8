"""``bezier.binomials`` gives scipy's binomial coefficients bit for bit (it replaces ``scipy.special.comb``)."""
import numpy as np
from scipy.special import comb

from c1surf.evaluation.bezier import binomials


def test_binomials_are_scipys():
    for degree in range(40):
        assert binomials(degree).tobytes() == comb(degree, np.arange(degree + 1)).tobytes()
