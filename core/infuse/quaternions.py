"""Quaternion maths on numpy arrays, vectorized over any leading shape.

Convention, used everywhere in infuse: quaternions are stored scalar-last ``(x, y, z, w)``,
like glTF and ``scipy.spatial.transform.Rotation``; they are unit quaternions acting on
column vectors (``rotate(q, v) = q v q*``), and ``multiply(a, b)`` applies ``b`` first, then ``a``.
Angles are radians unless a name ends in ``_deg``.

The conversions from and to rotation vectors, matrices and Euler angles go through scipy's
``Rotation``, imported on first use: importing scipy takes longer than most commands.
"""
from __future__ import annotations

import numpy as np

IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])

# The product and the rotation are quadratic: each output entry is a signed sum of products of one
# input component by another. On a few quaternions (a block of frames of one joint) numpy's cost per
# call outweighs the arithmetic, so they run as a few matrix products: ``a * b`` as ``L(a) b`` with
# ``L(a)`` gathered from ``a`` by a constant table, ``rotate`` as the outer product ``q q`` times a
# constant table (the rotation matrix) times ``v``. On many, the written-out component formulas stream
# through memory faster. Both agree to rounding.
#: Largest batch (quaternions in the larger operand) computed as small matrix products.
SMALL_BATCH = 512
_X, _Y, _Z, _W = range(4)
# Entry -> (sign, i, j) terms, meaning sign * a_i * b_j: the Hamilton product a * b ...
_PRODUCT_TERMS = {
    (_X,): ((1, _W, _X), (1, _X, _W), (1, _Y, _Z), (-1, _Z, _Y)),
    (_Y,): ((1, _W, _Y), (-1, _X, _Z), (1, _Y, _W), (1, _Z, _X)),
    (_Z,): ((1, _W, _Z), (1, _X, _Y), (-1, _Y, _X), (1, _Z, _W)),
    (_W,): ((1, _W, _W), (-1, _X, _X), (-1, _Y, _Y), (-1, _Z, _Z)),
}
# ... and the rotation matrix of q minus the identity (a_i = b_i = q_i).
_ROTATION_TERMS = {
    (0, 0): ((-2, _Y, _Y), (-2, _Z, _Z)), (0, 1): ((2, _X, _Y), (-2, _W, _Z)), (0, 2): ((2, _X, _Z), (2, _W, _Y)),
    (1, 0): ((2, _X, _Y), (2, _W, _Z)), (1, 1): ((-2, _X, _X), (-2, _Z, _Z)), (1, 2): ((2, _Y, _Z), (-2, _W, _X)),
    (2, 0): ((2, _X, _Z), (-2, _W, _Y)), (2, 1): ((2, _Y, _Z), (2, _W, _X)), (2, 2): ((-2, _X, _X), (-2, _Y, _Y)),
}


def _table(terms: dict, shape: tuple[int, ...]) -> np.ndarray:
    """(16, *shape) coefficients: row ``4 i + j`` holds the coefficient of ``a_i b_j`` in every entry."""
    table = np.zeros((4, 4) + shape)
    for entry, products in terms.items():
        for sign, i, j in products:
            table[(i, j) + entry] = sign
    return table.reshape((16,) + shape)


def _product_table(terms: dict, right: bool) -> tuple[np.ndarray, np.ndarray]:
    """(4, 4) index and sign of the matrix ``L(a)`` with ``a * b = L(a) b`` (``L(a)[r, j] = sign a_i`` for
    the term ``sign a_i b_j`` of entry ``r``; each entry has one term per ``j``), or with ``right`` of
    ``R(b)`` with ``a * b = R(b) a`` (``R(b)[r, i] = sign b_j``)."""
    index = np.zeros((4, 4), dtype=np.intp)
    signs = np.zeros((4, 4))
    for (r,), products in terms.items():
        for sign, i, j in products:
            if right:
                index[r, i], signs[r, i] = j, sign
            else:
                index[r, j], signs[r, j] = i, sign
    return index, signs


_LEFT_INDEX, _LEFT_SIGN = _product_table(_PRODUCT_TERMS, right=False)
_RIGHT_INDEX, _RIGHT_SIGN = _product_table(_PRODUCT_TERMS, right=True)
_ROTATION = _table(_ROTATION_TERMS, (3, 3))  # (16, 3, 3)
_ROTATION_FLAT = _ROTATION.reshape(16, 9)
_IDENTITY_FLAT = np.eye(3).ravel()


def identity(shape: tuple[int, ...] = ()) -> np.ndarray:
    """Identity quaternions of shape ``shape + (4,)``."""
    out = np.zeros(tuple(shape) + (4,))
    out[..., 3] = 1.0
    return out


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a * b`` (x,y,z,w), broadcast over leading axes."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if max(a.size, b.size) <= 4 * SMALL_BATCH:
        return (left_matrix(a) @ b[..., None])[..., 0]
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(a.shape if a.shape == b.shape else np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 1] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 2] = aw * bz + ax * by - ay * bx + az * bw
    out[..., 3] = aw * bw - ax * bx - ay * by - az * bz
    return out


def left_matrix(a: np.ndarray) -> np.ndarray:
    """(..., 4, 4) matrices ``L(a)`` of quaternions ``a`` (..., 4): ``multiply(a, b) = L(a) @ b`` for
    (x, y, z, w) columns ``b``. A product by the same ``a`` over many frames is then one matrix product."""
    return np.asarray(a, dtype=np.float64)[..., _LEFT_INDEX] * _LEFT_SIGN


def right_matrix(b: np.ndarray) -> np.ndarray:
    """(..., 4, 4) matrices ``R(b)`` of quaternions ``b`` (..., 4): ``multiply(a, b) = R(b) @ a``."""
    return np.asarray(b, dtype=np.float64)[..., _RIGHT_INDEX] * _RIGHT_SIGN


def conjugate(q: np.ndarray) -> np.ndarray:
    """Conjugate, the inverse of a unit quaternion (x,y,z,w)."""
    out = np.array(q, dtype=np.float64, copy=True)
    out[..., :3] *= -1.0
    return out


inverse = conjugate


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors ``v`` (...,3) by unit quaternions ``q`` (...,4, x,y,z,w)."""
    q = np.asarray(q, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    if max(q.size // 4, v.size // 3) <= SMALL_BATCH:
        outer = (q[..., :, None] * q[..., None, :]).reshape(-1, 16)  # q_i q_j at 4 i + j, one row per quaternion
        if v.ndim == 1:  # one vector for every quaternion: the table times the vector first
            return v + (outer @ (_ROTATION @ v)).reshape(q.shape[:-1] + (3,))
        matrices = (outer @ _ROTATION_FLAT).reshape(q.shape[:-1] + (3, 3))
        return v + (matrices @ v[..., None])[..., 0]
    lead = q.shape[:-1] if q.shape[:-1] == v.shape[:-1] else np.broadcast_shapes(q.shape[:-1], v.shape[:-1])
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    vx, vy, vz = v[..., 0], v[..., 1], v[..., 2]
    # v + w t + u x t with t = 2 (u x v), written out: np.cross is slow on small arrays.
    tx = 2.0 * (y * vz - z * vy)
    ty = 2.0 * (z * vx - x * vz)
    tz = 2.0 * (x * vy - y * vx)
    out = np.empty(lead + (3,))
    out[..., 0] = vx + w * tx + (y * tz - z * ty)
    out[..., 1] = vy + w * ty + (z * tx - x * tz)
    out[..., 2] = vz + w * tz + (x * ty - y * tx)
    return out


def normalize(q: np.ndarray) -> np.ndarray:
    """Unit-length quaternions; a zero quaternion becomes the identity."""
    q = np.asarray(q, dtype=np.float64)
    n = np.sqrt(np.einsum("...i,...i->...", q, q))[..., None]
    safe = n > 1e-12
    if safe.all():
        return q / n
    return np.where(safe, q / np.where(safe, n, 1.0), IDENTITY)


def canonical_sign(q: np.ndarray) -> np.ndarray:
    """The same rotations with w >= 0 (q and -q are one rotation)."""
    q = np.asarray(q, dtype=np.float64)
    return np.where(q[..., 3:4] < 0.0, -q, q)


def make_continuous(q: np.ndarray, axis: int = 0) -> np.ndarray:
    """Flip signs along ``axis`` (frames) so neighbouring quaternions lie in one hemisphere."""
    q = np.moveaxis(np.array(q, dtype=np.float64, copy=True), axis, 0)
    dots = np.sum(q[1:] * q[:-1], axis=-1)
    flips = np.cumsum(dots < 0.0, axis=0) % 2
    q[1:][flips.astype(bool)] *= -1.0
    return np.moveaxis(q, 0, axis)


def from_axis_angle(axis: np.ndarray, angle: np.ndarray | float) -> np.ndarray:
    """Quaternions from unit ``axis`` (...,3) and ``angle`` in radians (...)."""
    axis = np.asarray(axis, dtype=np.float64)
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    return np.concatenate((axis * np.sin(half), np.cos(half)), axis=-1)


def _rotation():
    from scipy.spatial.transform import Rotation

    return Rotation


def from_rotvec(rotvec: np.ndarray) -> np.ndarray:
    """Quaternions from rotation vectors (axis * angle, radians), shape (...,3)."""
    rotvec = np.asarray(rotvec, dtype=np.float64)
    shape = rotvec.shape[:-1]
    return _rotation().from_rotvec(rotvec.reshape(-1, 3)).as_quat().reshape(shape + (4,))


def to_rotvec(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (axis * angle, radians, angle in [0, pi]) from quaternions (...,4)."""
    q = np.asarray(q, dtype=np.float64)
    shape = q.shape[:-1]
    return _rotation().from_quat(q.reshape(-1, 4)).as_rotvec().reshape(shape + (3,))


def from_matrix(m: np.ndarray) -> np.ndarray:
    """Quaternions from rotation matrices (...,3,3) acting on column vectors."""
    m = np.asarray(m, dtype=np.float64)
    shape = m.shape[:-2]
    return _rotation().from_matrix(m.reshape(-1, 3, 3)).as_quat().reshape(shape + (4,))


def to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (...,3,3) from quaternions (...,4), normalized first (a zero one is the identity)."""
    return unit_to_matrix(normalize(q))


def unit_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (...,3,3) acting on column vectors, of unit quaternions (...,4).

    Unlike :func:`to_matrix` the quaternions are taken as unit length (not normalized): the matrices
    come from their products in one table product, cheap on a few quaternions as on many.
    """
    q = np.asarray(q, dtype=np.float64)
    outer = (q[..., :, None] * q[..., None, :]).reshape(-1, 16)  # q_i q_j at 4 i + j, one row per quaternion
    return (outer @ _ROTATION_FLAT + _IDENTITY_FLAT).reshape(q.shape[:-1] + (3, 3))


def from_euler(order: str, angles: np.ndarray, degrees: bool = False) -> np.ndarray:
    """Quaternions from intrinsic Euler angles.

    ``order`` is a string such as ``"ZXY"``: the rotation is R = R_Z(a0) R_X(a1) R_Y(a2), the
    convention of BVH channel lists (the first listed axis is outermost). ``angles`` is (...,3).
    """
    angles = np.asarray(angles, dtype=np.float64)
    shape = angles.shape[:-1]
    rot = _rotation().from_euler(order.upper(), angles.reshape(-1, 3), degrees=degrees)
    return rot.as_quat().reshape(shape + (4,))


def to_euler(order: str, q: np.ndarray, degrees: bool = False) -> np.ndarray:
    """Intrinsic Euler angles (...,3) in ``order`` (see :func:`from_euler`) from quaternions."""
    q = np.asarray(q, dtype=np.float64)
    shape = q.shape[:-1]
    rot = _rotation().from_quat(q.reshape(-1, 4))
    return rot.as_euler(order.upper(), degrees=degrees).reshape(shape + (3,))


def between(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Shortest-arc rotations taking directions ``u`` to ``v`` (...,3); need not be unit length."""
    u = np.asarray(u, dtype=np.float64)
    v = np.asarray(v, dtype=np.float64)
    u = u / np.maximum(np.linalg.norm(u, axis=-1, keepdims=True), 1e-12)
    v = v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)
    d = np.sum(u * v, axis=-1, keepdims=True)
    c = np.cross(u, v)
    q = np.concatenate((c, 1.0 + d), axis=-1)
    # Opposite directions: rotate by pi about any axis orthogonal to u.
    opposite = (1.0 + d[..., 0]) < 1e-9
    if np.any(opposite):
        ortho = np.cross(u, np.array([1.0, 0.0, 0.0]))
        small = np.linalg.norm(ortho, axis=-1) < 1e-6
        ortho = np.where(small[..., None], np.cross(u, np.array([0.0, 1.0, 0.0])), ortho)
        q = np.where(opposite[..., None], np.concatenate((ortho, np.zeros_like(d)), axis=-1), q)
    return normalize(q)


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Rotation angle in radians, in [0, pi], of ``a^-1 b``."""
    d = np.abs(np.sum(normalize(a) * normalize(b), axis=-1))
    return 2.0 * np.arccos(np.clip(d, 0.0, 1.0))


def slerp(a: np.ndarray, b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Spherical interpolation from ``a`` (t=0) to ``b`` (t=1), shortest path; ``t`` broadcasts."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    t = np.asarray(t, dtype=np.float64)[..., None]
    d = np.einsum("...i,...i->...", a, b)[..., None]
    b = np.where(d < 0.0, -b, b)
    theta = np.arccos(np.minimum(np.abs(d), 1.0))
    s = np.sin(theta)
    near = s < 1e-6  # (nearly) the same rotation: a plain lerp
    if near.any():
        safe_s = np.where(near, 1.0, s)
        wa = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) / safe_s)
        wb = np.where(near, t, np.sin(t * theta) / safe_s)
    else:
        wa = np.sin((1.0 - t) * theta) / s
        wb = np.sin(t * theta) / s
    return normalize(wa * a + wb * b)
