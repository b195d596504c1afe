"""Stratified sample patterns for renders: correlated multi-jittered samples computed per sample
index, so a pixel's samples may be drawn in any number of passes and still form one stratified set.
`permute` and `cmj_2d` follow Kensler's hashed permutation and correlated multi-jittered pattern.

All functions take and return Dr.Jit arrays of the current Mitsuba variant (`mi.UInt32`, `mi.Float`);
`stratified_1d` and `cmj_2d` return points in [0, 1) (unitless).

Reference: A. Kensler, "Correlated Multi-Jittered Sampling", Pixar Technical Memo 13-01, 2013.
"""

from __future__ import annotations

import drjit as dr
import mitsuba as mi


def _mask(n: int) -> int:
    w = max(n - 1, 0)
    for shift in (1, 2, 4, 8, 16):
        w |= w >> shift
    return w


def _scramble(i, w: int, p):
    i ^= p
    i *= 0xE170893D
    i ^= p >> 16
    i ^= (i & w) >> 4
    i ^= p >> 8
    i *= 0x0929EB3F
    i ^= p >> 23
    i ^= (i & w) >> 1
    i *= 1 | p >> 27
    i *= 0x6935FA69
    i ^= (i & w) >> 11
    i *= 0x74DCB303
    i ^= (i & w) >> 2
    i *= 0x9E501CC3
    i ^= (i & w) >> 2
    i *= 0xC860A3DF
    i &= w
    i ^= i >> 5
    return i


def permute(i, n: int, p):
    """A pseudo-random permutation of 0…n−1 chosen by the seed p (per element), applied to i < n."""
    w = _mask(n)
    i = _scramble(mi.UInt32(i), w, p)
    i = dr.while_loop(state=(i, mi.UInt32(p)), cond=lambda i, p: i >= n, body=lambda i, p: (_scramble(i, w, p), p))[0]
    return (i + p) % n


def hash_seed(*values) -> mi.UInt32:
    """A 32-bit seed mixed from integers or UInt32 arrays (per element)."""
    h = mi.UInt32(0x9E3779B9)
    for v in values:
        h ^= mi.UInt32(v) + 0x7F4A7C15 + (h << 6) + (h >> 2)
        h *= 0x85EBCA6B
        h ^= h >> 13
    return h


def stratified_1d(s, n: int, seed, jitter):
    """Sample s of n one-dimensional strata, in a random stratum order per seed."""
    return (mi.Float(permute(s, n, seed)) + jitter) / n


def cmj_2d(s, n: int, seed, jitter: mi.Point2f) -> mi.Point2f:
    """Sample s of a correlated multi-jittered set of n points in [0, 1)² on an m×k grid: m·k = n
    when n has a divisor near √n, else n random slots of a grid slightly larger (still uniform)."""
    root = max(1, int(n**0.5))
    m = next(d for d in range(root, 0, -1) if n % d == 0)
    if 2 * m < root:  # no useful factorisation: leave a few slots empty instead
        m = root
    k = -(-n // m)
    s = permute(s, m * k, seed * 0x51633E2D)
    sx = permute(s % m, m, seed * 0x68BC21EB)
    sy = permute(s // m, k, seed * 0x02E5BE93)
    x = (mi.Float(s % m) + (mi.Float(sy) + jitter.x) / k) / m
    y = (mi.Float(s // m) + (mi.Float(sx) + jitter.y) / m) / k
    return mi.Point2f(x, y)
