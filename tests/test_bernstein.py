"""Bernstein conversion and splitting against direct evaluation."""

import numpy as np
import pytest
from scipy.special import comb

from singmesh.boxes.bernstein import bernstein_on_box, evaluate_1d, split, split_matrices


def eval_bernstein(tensor, t):
    """Direct evaluation of a tensor-product Bernstein form at local t in [0,1]^3."""
    basis = []
    for a in range(3):
        n = tensor.shape[a] - 1
        i = np.arange(n + 1)
        basis.append(comb(n, i) * t[a] ** i * (1 - t[a]) ** (n - i))
    return np.einsum("i,j,k,ijk->", *basis, tensor)


def eval_monomial(coeffs, p):
    total = 0.0
    for (i, j, k), c in np.ndenumerate(coeffs):
        total += c * p[0] ** i * p[1] ** j * p[2] ** k
    return total


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_conversion_matches_direct_evaluation(seed):
    rng = np.random.default_rng(seed)
    coeffs = rng.normal(size=(4, 3, 5))
    box = np.sort(rng.uniform(-3, 3, size=(3, 2)), axis=1)
    tensor = bernstein_on_box(coeffs, box)
    for _ in range(25):
        t = rng.random(3)
        p = box[:, 0] + t * (box[:, 1] - box[:, 0])
        assert eval_bernstein(tensor, t) == pytest.approx(eval_monomial(coeffs, p), abs=1e-11)


def test_corner_coefficients_are_values():
    rng = np.random.default_rng(5)
    coeffs = rng.normal(size=(3, 3, 3))
    box = np.array([[-1.0, 2.0], [0.5, 1.5], [-2.0, -1.0]])
    tensor = bernstein_on_box(coeffs, box)
    for idx in np.ndindex(2, 2, 2):
        p = box[np.arange(3), idx]
        corner = tuple(-1 if i else 0 for i in idx)
        assert tensor[corner] == pytest.approx(eval_monomial(coeffs, p), abs=1e-12)


def test_split_children_agree_with_parent():
    rng = np.random.default_rng(3)
    parent = rng.normal(size=(2, 4, 5, 3))
    children = split(parent)
    assert children.shape == (2, 2, 2, 2, 4, 5, 3)
    for m in range(2):
        for c in np.ndindex(2, 2, 2):
            for _ in range(10):
                t = rng.random(3)
                tp = (t + np.array(c)) / 2
                assert eval_bernstein(children[(m,) + c], t) == pytest.approx(
                    eval_bernstein(parent[m], tp), abs=1e-12)


def test_split_matrices_are_exact_dyadic():
    # Splitting at 1/2 involves only dyadic rationals: entries times 2^n are integers.
    left, right = split_matrices(7)
    assert np.array_equal(left * 2**7, np.round(left * 2**7))
    assert np.array_equal(right * 2**7, np.round(right * 2**7))
    assert np.allclose(left.sum(axis=1), 1) and np.allclose(right.sum(axis=1), 1)


def test_evaluate_1d():
    rng = np.random.default_rng(4)
    b = rng.normal(size=(6, 5))
    t = rng.random(6)
    n = 4
    i = np.arange(n + 1)
    direct = (b * comb(n, i) * t[:, None] ** i * (1 - t[:, None]) ** (n - i)).sum(axis=1)
    assert np.allclose(evaluate_1d(b, t), direct, atol=1e-13)


def test_simplicity_axis_is_the_first_that_passes():
    """monotone_axis skips axes on boxes an earlier one passed: the answer
    is still the first axis (in 0, 1, 2) whose derivative has one sign and
    whose two end faces hold no closed curve, checked here box by box."""
    from singmesh.boxes.polynomial_bounds import monotone_axis

    def one_sign(c):
        return (c.min() >= 0 and c.max() > 0) or (c.max() <= 0 and c.min() < 0)

    def no_loop(face):
        return (one_sign(np.diff(face, axis=0)) or one_sign(np.diff(face, axis=1))
                or face.min() >= 0 or face.max() < 0)

    rng = np.random.default_rng(11)
    # Tensors that pass on various axes: a ramp along a random axis plus noise.
    tensors = rng.normal(size=(400, 4, 3, 5)) * rng.choice([0.05, 1.0], size=(400, 1, 1, 1))
    ramp = [np.arange(n)[tuple(slice(None) if b == a else None for b in range(3))] for a, n in enumerate((4, 3, 5))]
    for m in range(len(tensors)):
        tensors[m] += ramp[rng.integers(3)] - 1.0
    got = monotone_axis(tensors)
    want = np.full(len(tensors), -1)
    for m, t in enumerate(tensors):
        for a in range(3):
            if one_sign(np.diff(t, axis=a)) and no_loop(np.take(t, 0, axis=a)) and no_loop(np.take(t, -1, axis=a)):
                want[m] = a
                break
    assert np.array_equal(got, want)
    assert {0, 1, 2, -1} <= set(want.tolist())  # every outcome is exercised


def test_mixed_corners_and_empty_boxes_against_all_coefficients():
    """empty_boxes reads the corners first (mixed_corners: F of both strict
    signs there, so not empty) and all coefficients only for the others:
    the same answers as the test on all coefficients, on random stacks,
    stacks with zeros at corners or everywhere, a degree 0 axis, and none."""
    from singmesh import tolerances as tol
    from singmesh.boxes.polynomial_bounds import empty_boxes, mixed_corners

    def reference(t):
        flat = t.reshape(len(t), int(np.prod(t.shape[1:])))
        lo, hi = flat.min(axis=1, initial=np.inf), flat.max(axis=1, initial=-np.inf)
        slack = tol.PRUNE_SLACK * np.maximum(hi, -lo)
        return (lo > slack) | (hi < -slack)

    def corners(t):
        c = np.array([t[:, i, j, k] for i in {0, t.shape[1] - 1} for j in {0, t.shape[2] - 1}
                      for k in {0, t.shape[3] - 1}])
        return (c < 0).any(axis=0) & (c > 0).any(axis=0)

    rng = np.random.default_rng(5)
    stacks = [rng.normal(size=(500, 5, 5, 5)) + rng.choice([0.0, 3.0, -3.0], size=(500, 1, 1, 1)),
              rng.normal(size=(200, 1, 3, 2)) + 1.5, rng.normal(size=(100, 4, 2, 6)), np.zeros((3, 5, 5, 5)),
              np.zeros((0, 5, 5, 5))]
    z = rng.normal(size=(300, 5, 5, 5)) + 2.0
    z[:, ::4, ::4, ::4] = rng.choice([0.0, -0.0, 1.0, -1e-17], size=(300, 2, 2, 2))
    stacks.append(z)
    # NaN at corners (both signs elsewhere still count), and views that are
    # not C-contiguous (the corners are then gathered from the view itself).
    w = rng.normal(size=(200, 5, 4, 3))
    w[:, 0, 0, 0] = np.where(rng.random(200) < 0.3, np.nan, w[:, 0, 0, 0])
    stacks.append(w)
    for t in stacks:
        assert np.array_equal(mixed_corners(t), corners(t))
        assert np.array_equal(empty_boxes(t), reference(t))
    for view in [np.swapaxes(np.swapaxes(stacks[0], 1, 3).copy(), 1, 3), stacks[2][::2], w[:, ::-1]]:
        assert not view.flags.c_contiguous
        assert np.array_equal(mixed_corners(view), corners(view))
    assert mixed_corners(stacks[0]).any() and empty_boxes(stacks[0]).any() and not empty_boxes(stacks[0]).all()


def test_may_vanish_ands_each_boxs_tests():
    """may_vanish tests the derivatives before F, each on the boxes still kept: the
    answer is every box's four tests and-ed, checked here box by box (coefficients of
    F and of its differences along each axis within the slack of their largest, or
    within the dust), on random stacks, with zeros, a degree 0 axis and none."""
    from singmesh import tolerances as tol
    from singmesh.boxes.polynomial_bounds import may_vanish

    def holds_zero(c, dust):
        if c.size == 0:
            return True
        slack = max(tol.CANDIDATE_SLACK * max(c.max(), -c.min()), dust)
        return c.min() <= slack and c.max() >= -slack

    rng = np.random.default_rng(12)
    t = rng.normal(size=(600, 4, 3, 5)) * rng.choice([0.05, 1.0], size=(600, 1, 1, 1))
    t += rng.choice([0.0, 0.2, -0.2], size=(600, 1, 1, 1))
    t[:50] = 0.0
    t[50:80, :, 0] = 1e-18
    for stack, axes, dust in [(t, (0, 1, 2), 0.0), (t, (0, 2), 1e-3), (t[:, :, :1], (0, 1, 2), 0.0),
                              (t[:0], (0, 1, 2), 0.0)]:
        got = may_vanish(stack, axes, dust)
        want = [holds_zero(b, dust) and all(holds_zero(np.diff(b, axis=a), dust) for a in axes if b.shape[a] > 1)
                for b in stack]
        assert np.array_equal(got, np.array(want, bool).reshape(-1))
    assert may_vanish(t, (0, 1, 2), 0.0).any() and not may_vanish(t, (0, 1, 2), 0.0).all()


def _split_by_small_products(tensors):
    """The split as main computed it before the eleventh speed pass: axis 0, then axis 1 as a
    batch of small products per child half, then axis 2 per child half (the reference)."""
    n = tensors.shape[0]
    n0, n1, n2 = tensors.shape[1:]
    m = [split_matrices(d - 1) for d in (n0, n1, n2)]
    out = np.empty((n, 2, 2, 2, n0, n1, n2))
    a = np.matmul(np.stack(m[0])[None], tensors.reshape(n, 1, n0, n1 * n2))
    a = a.reshape(n * 2 * n0, n1, n2)
    for q in range(2):
        b = np.matmul(m[1][q], a).reshape(-1, n2)
        for r in range(2):
            out[:, :, q, r] = (b @ m[2][r].T).reshape(n, 2, n0, n1, n2)
    return out


@pytest.mark.parametrize("shape", [(256, 5, 5, 5), (1, 5, 5, 5), (0, 5, 5, 5), (37, 4, 2, 7),
                                   (5, 1, 3, 1), (9, 1, 1, 1), (3, 7, 7, 7), (64, 3, 6, 2)])
def test_split_is_the_sums_of_small_products_bit_for_bit(shape):
    # The same coefficients, bit for bit, as the computation it replaces (the same
    # sums in the same order), on random stacks of many scales, with zeros, ties and
    # signed zeros among them.
    rng = np.random.default_rng(sum(shape))
    for trial in range(6):
        t = rng.standard_normal(shape) * 10.0 ** rng.integers(-12, 12, size=shape)
        if trial == 1:
            t = np.round(t)  # integers and many zeros
        if trial == 2:
            t[..., ::2] = -0.0
        got, want = split(t), _split_by_small_products(t)
        assert got.shape == want.shape == (shape[0], 2, 2, 2) + shape[1:]
        assert got.tobytes() == want.tobytes()


def test_split_of_constant_and_linear_stacks_is_exact():
    # Degree 0 and 1 along some axes, from the degenerate to the usual: the children of
    # a constant are the constant, of a linear form its values at the halves.
    c = np.full((4, 1, 1, 1), 2.5)
    assert np.array_equal(split(c), np.full((4, 2, 2, 2, 1, 1, 1), 2.5))
    lin = np.array([[[[0.0, 1.0]]]]).repeat(3, axis=0)  # t2 on [0, 1]
    kids = split(lin)
    assert np.array_equal(kids[:, :, :, 0, 0, 0], np.broadcast_to([0.0, 0.5], (3, 2, 2, 2)))
    assert np.array_equal(kids[:, :, :, 1, 0, 0], np.broadcast_to([0.5, 1.0], (3, 2, 2, 2)))
