#!/usr/bin/env python3
"""Incremental (Biot) stability of the two-grain block's frictionless interface (issue 14).

The walled two-grain block (tests/verification/wall_block, `two_grains = true`) is two identical
compressible Neo-Hookean blocks, each in uniaxial strain F = diag(1, s), pressed together through a
frictionless horizontal interface (normal e2). Does the continuum lose stability there, so that the
exact homogeneous state is not the one to demand? This script answers with the classical surface
analysis of a pre-stressed half-space (Biot 1965, Mechanics of Incremental Deformations, ch. 7;
Ogden, Non-linear Elastic Deformations, §6.2).

Incremental equations, current configuration (updated Lagrangian): the nominal stress rate
  dP_ij = A_ijkl u_k,l,   A_ijkl = c_ijkl + delta_ik sigma_jl                          (1)
with, for the law of method.md (S = (lambda ln J - mu) C^-1 + mu I),
  J c_ijkl = lambda delta_ij delta_kl + (mu - lambda ln J)(delta_ik delta_jl + delta_il delta_jk)  (2)
and dP_ij,j = 0 in each block. Modes u1 = a sin(kx) e^{kqy}, u2 = b cos(kx) e^{kqy} (half-space
y < 0, Re q > 0) give the biquadratic
  (A1212 q^2 - A1111)(A2222 q^2 - A2121) + (A1122 + A1221)^2 q^2 = 0.                      (3)
The interface carries a pressure p = -sigma22 along its current normal (frictionless), so on each
side the nominal traction rate is
  dP_12 = p u2,1,   dP_22 = -dp - p u1,1.                                                  (4)
For two identical blocks every mode splits into a mirror one (u2 = 0 on the interface: a block on a
frictionless rigid wall, dP_12 = 0) and an antisymmetric one (u2 continuous, u1 opposite, dp = 0:
each block a half-space under a follower pressure). The state is stable while the 2x2 boundary
determinant of each keeps its sign from s = 1 (no surface mode of zero frequency).

Checks (--check, run by ctest): the script reproduces Biot's critical stretch 0.5437 of a nearly
incompressible half-space compressed along its free surface (plane strain), then reports, for the
block's lambda = 0, 3, 100 MPa (mu = 1.5 MPa) down to s = 0.3, where each interface mode would
first become unstable. Variants of (4) show what the interface's discrete counterpart must keep:
without the stretch term of dP_22 the antisymmetric mode stays stable, but with neither follower
term (a dead load: the pressure's direction and its force per reference length fixed) it becomes
unstable at sigma22 of -1.6 to -2 mu.

Usage: interface_stability.py [--check]
"""
import sys

import numpy as np

MU = 1.5e6  # [Pa], the block tests' shear modulus


def moduli(lam, mu, l1, l2):
    """A_ijkl of (1)-(2) [Pa] and the Cauchy stresses at F = diag(l1, l2)."""
    J = l1 * l2
    m = mu - lam * np.log(J)
    s11 = (mu * (l1 * l1 - 1) + lam * np.log(J)) / J
    s22 = (mu * (l2 * l2 - 1) + lam * np.log(J)) / J
    return dict(A1111=(lam + 2 * m) / J + s11, A2222=(lam + 2 * m) / J + s22, A1122=lam / J,
                A1212=m / J + s22, A2121=m / J + s11, A1221=m / J, s11=s11, s22=s22)


def modes(d, both_signs):
    """The modes of eq. (3) [-]: per root q (Re q >= 0, and -q too when `both_signs`), with the
    amplitudes (a, b) from the first row of (3)'s 2x2 system, normalised, and the traction rates
    dP_12 / sin(kx) and dP_22 / cos(kx) on a face y = const, as (q, a, b, shear, normal)."""
    c = d['A1122'] + d['A1221']
    roots = np.roots([d['A1212'] * d['A2222'],
                      c * c - d['A1212'] * d['A2121'] - d['A1111'] * d['A2222'],
                      d['A1111'] * d['A2121']])  # eq. (3) in q^2
    out = []
    for Q in roots:
        q0 = np.sqrt(complex(Q))
        if q0.real < 0:
            q0 = -q0
        for q in ((q0, -q0) if both_signs else (q0,)):
            a, b = c * q, d['A1212'] * q * q - d['A1111']
            n = np.hypot(abs(a), abs(b))
            a, b = a / n, b / n
            out.append((q, a, b, d['A1212'] * q * a - d['A1221'] * b,
                        d['A1122'] * a + d['A2222'] * q * b))
    return out


def interface_rows(d, a, b, shear, normal, bc):
    """The two conditions of `bc` at the interface y = 0 for one mode (see boundary_det)."""
    if bc == 'wall':
        return shear, b
    follow_shear = bc in ('follower', 'nominal')
    follow_normal = bc == 'follower'
    # dP_12 - p u2,1 = 0 with u2,1 = -b sin; dP_22 + p u1,1 = 0 with u1,1 = a cos (eq. 4)
    return (shear - (d['s22'] * b if follow_shear else 0),
            normal - (d['s22'] * a if follow_normal else 0))


def boundary_det(lam, mu, l1, l2, bc):
    """Boundary determinant of the half-space y < 0 for the conditions `bc` at y = 0 [-].

    bc: 'follower' (eq. 4, dp = 0: the antisymmetric interface mode), 'nominal' (eq. 4 without
    the stretch term of dP_22), 'dead' (neither follower term), 'wall' (u2 = 0, dP_12 = 0: the
    mirror mode; a rigid frictionless wall)."""
    d = moduli(lam, mu, l1, l2)
    M = np.zeros((2, 2), complex)
    for j, (q, a, b, shear, normal) in enumerate(modes(d, False)):
        M[:, j] = interface_rows(d, a, b, shear, normal, bc)
    return np.linalg.det(M).real


def layer_det(lam, mu, s, kH, bc):
    """Boundary determinant of one grain of the block, the layer -H < y < 0 (current height H,
    kH = k H): a rigid frictionless wall at y = -H (u2 = 0, dP_12 = 0) and the interface at y = 0
    with the conditions `bc` of boundary_det [-]."""
    d = moduli(lam, mu, 1.0, s)
    M = np.zeros((4, 4), complex)
    # both decaying and growing with depth in a layer
    for j, (q, a, b, shear, normal) in enumerate(modes(d, True)):
        e = np.exp(-q * kH)
        M[:, j] = (*interface_rows(d, a, b, shear, normal, bc), shear * e, b * e)
    return np.linalg.det(M).real


def first_sign_change(f, start, stop, samples=4000):
    """Largest x in [stop, start] where f changes sign, scanning down from start, refined by
    bisection; None if f keeps its sign."""
    xs = np.linspace(start, stop, samples)
    prev = f(xs[0])
    for x0, x1 in zip(xs[:-1], xs[1:]):
        v = f(x1)
        if np.sign(v) != np.sign(prev):
            hi, lo = x0, x1
            for _ in range(60):
                mid = 0.5 * (hi + lo)
                if np.sign(f(mid)) == np.sign(prev):
                    hi = mid
                else:
                    lo = mid
            return 0.5 * (hi + lo)
        prev = v
    return None


def biot_critical_stretch(lam_over_mu):
    """Critical stretch along the free surface of a half-space in plane-strain uniaxial stress."""
    mu = 1.0
    lam = lam_over_mu * mu

    def normal_stretch(l1):  # sigma22 = 0 by bisection
        lo, hi = 0.1, 20.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if moduli(lam, mu, l1, mid)['s22'] > 0:
                hi = mid
            else:
                lo = mid
        return 0.5 * (lo + hi)

    return first_sign_change(lambda l1: boundary_det(lam, mu, l1, normal_stretch(l1), 'dead'),
                             0.99, 0.3, 700)


def main():
    check = '--check' in sys.argv
    ok = True
    sc = biot_critical_stretch(1e4)
    print(f'Biot, nearly incompressible (lambda/mu = 1e4), free surface: critical stretch {sc:.4f}'
          ' (Biot 1965: 0.5437)')
    ok &= sc is not None and abs(sc - 0.5437) < 2e-3
    print('Two-grain block, uniaxial strain F = diag(1, s), s from 1 to 0.3 (mu = 1.5 MPa):')
    print('| lambda | mirror mode (rigid wall) | antisymmetric mode (follower pressure) |'
          ' nominal pressure not following the stretch | dead load |')
    print('| --- | --- | --- | --- | --- |')
    for lam in (0.0, 3e6, 1e8):
        row = []
        for bc in ('wall', 'follower', 'nominal', 'dead'):
            s = first_sign_change(lambda s: boundary_det(lam, MU, 1.0, s, bc), 0.9999, 0.3)
            if s is None:
                row.append('stable')
            else:
                row.append(f's = {s:.4f} (sigma22 = {moduli(lam, MU, 1.0, s)["s22"] / MU:.2f} mu)')
            if bc in ('wall', 'follower'):
                ok &= s is None  # the continuum interface is stable in both modes
        print(f'| {lam / 1e6:g} MPa | ' + ' | '.join(row) + ' |')
    # The block itself: width W = 1 mm between frictionless side walls (u1 ~ sin(n pi x / W)),
    # each grain H = 0.5 s mm high (tests/verification/wall_block, two_grains).
    print('The two-grain block (W = 1 mm, each grain 0.5 s mm high), antisymmetric mode n:')
    print('| lambda | n | follower pressure (the continuum) | dead load |')
    print('| --- | --- | --- | --- |')
    for lam in (0.0, 3e6, 1e8):
        for n in (1, 2, 3, 5, 10):
            row = []
            for bc in ('follower', 'dead'):
                kH = lambda s: n * np.pi * 0.5 * s
                ref = layer_det(lam, MU, 0.9999, kH(0.9999), bc)
                s = first_sign_change(lambda s: layer_det(lam, MU, s, kH(s), bc) / ref,
                                      0.9999, 0.3, 2000)
                row.append('stable' if s is None else f's = {s:.4f}')
                if bc == 'follower':
                    ok &= s is None
            print(f'| {lam / 1e6:g} MPa | {n} | ' + ' | '.join(row) + ' |')
    if check and not ok:
        print('FAILED', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
