#!/usr/bin/env python3
"""Reference event times for test_exact.cpp, from the energy integral by 40-digit quadrature
(mpmath, Debian's python3-mpmath). Independent of the C++ closed form: no Jacobi functions, no
series, no Cayley-Klein parameters; only u'^2 D(u) = f(u) (PHYSICS.md, "Invariants") and
R = m (g + h u'') integrated with tanh-sinh quadrature after removing the square-root end
singularity at a turning point (u = u_turn -+ s^2).

Usage: /usr/bin/python3 test/reference/exact_references.py
"""
import mpmath as mp

mp.mp.dps = 40


class Reduced:
    """u = cos(theta) of a top in the fixed-tip or frictionless scene, from Euler-angle rates."""

    def __init__(self, scene, m, A, C, h, g, tilt, precession, nutation, spin):
        m, A, C, h, g = map(mp.mpf, (m, A, C, h, g))
        tilt, precession, nutation, spin = map(mp.mpf, (tilt, precession, nutation, spin))
        self.Ap = A + m * h * h if scene == 'fixed_tip' else A
        self.alpha = 0 if scene == 'fixed_tip' else m * h * h / A
        self.m, self.g, self.h = m, g, h
        self.kappa = 2 * m * g * h / self.Ap
        self.c = C * spin / self.Ap
        self.u0 = mp.cos(tilt)
        s2 = mp.sin(tilt) ** 2
        self.udot0 = -mp.sin(tilt) * nutation
        self.k0 = nutation ** 2 + s2 * precession ** 2 + self.alpha * self.udot0 ** 2  # K(u0)
        self.p0 = s2 * precession  # p(u0) = sin^2 phidot

    def f(self, u):
        K = self.k0 - self.kappa * (u - self.u0)
        p = self.p0 - self.c * (u - self.u0)
        return K * (1 - u * u) - p * p

    def D(self, u):
        return 1 + self.alpha * (1 - u * u)

    def R(self, u):
        f, D = self.f(u), self.D(u)
        df, dD = mp.diff(self.f, u), -2 * self.alpha * u
        return self.m * (self.g + self.h * (df * D - f * dD) / (2 * D * D))

    def time(self, u_turn, u_from, u_to):
        """Time for u to run monotonically between u_from and u_to, both on the same side of the
        turning point u_turn (a simple root of f) or at it; u = u_turn + sigma s^2 there."""
        sigma = 1 if max(u_from, u_to) > u_turn else -1
        # f(u_turn + v) = a1 v + a2 v^2 + a3 v^3 (a0 = f(u_turn) = 0): divided by v exactly.
        coefficients = mp.taylor(self.f, u_turn, 3)
        quotient = lambda u: coefficients[1] + coefficients[2] * (u - u_turn) + coefficients[3] * (u - u_turn) ** 2
        integrand = lambda s: 2 * mp.sqrt(self.D(u_turn + sigma * s * s) / (sigma * quotient(u_turn + sigma * s * s)))
        a, b = mp.sqrt(abs(u_from - u_turn)), mp.sqrt(abs(u_to - u_turn))
        lo, hi = min(a, b), max(a, b)
        points = [lo] + [lo + (hi - lo) * mp.mpf(10) ** (-k) for k in range(12, 0, -1)] + [hi]
        return mp.quad(integrand, points)


def lower_root(top):
    """The largest root of f below u0 (the lower turning point u1)."""
    u = top.u0
    step = mp.mpf('1e-3')
    while top.f(u - step) > 0:
        u -= step
    return mp.findroot(top.f, (u - step, u), solver='bisect' if False else 'anderson')


def main():
    toy = dict(m='0.1', A='4e-5', C='6e-5', h='0.02', g='9.80665')
    for scene in ('fixed_tip', 'frictionless'):
        # A spinless top released at rest 1e-6 rad from the vertical: u0 is the upper turning
        # point, and it falls through u = 0.
        top = Reduced(scene, tilt='1e-6', precession=0, nutation=0, spin=0, **toy)
        print(scene, 'spinless fall from 1e-6 rad:', mp.nstr(top.time(top.u0, top.u0, 0), 20), 's')
        # An unstable sleeping top: half the critical spin 2 sqrt(A' m g h) / C, same release.
        Ap = top.Ap
        spin = mp.sqrt(Ap * top.m * top.g * top.h) / mp.mpf(toy['C'])
        top = Reduced(scene, tilt='1e-6', precession=0, nutation=0, spin=spin, **toy)
        print(scene, 'unstable sleeping top, spin', mp.nstr(spin, 17), 'rad/s, falls at:',
              mp.nstr(top.time(top.u0, top.u0, 0), 20), 's')
    # The frictionless top of the second reproduction: thetadot0 > 0, so u falls to the
    # lower turning point u1 first, then rises towards u2; R dips below zero for ~0.12 ms just
    # below u2 (the least tilt), where the rising branch first meets R = 0 at u_r.
    top = Reduced('frictionless', m='0.1', A='4e-5', C='6e-5', h='0.02', g='9.81', tilt='0.5', precession=0,
                  nutation='4.922', spin=150)
    u1 = mp.findroot(top.f, (top.u0 - mp.mpf('0.02'), top.u0 - mp.mpf('0.01')), solver='bisect')
    u2 = mp.findroot(top.f, (top.u0 + mp.mpf('1e-12'), mp.mpf(1)), solver='bisect')
    grid = [u1 + (u2 - u1) * k / 4000 for k in range(4001)]
    first = next(k for k in range(4001) if top.R(grid[k]) < 0)
    u_r = mp.findroot(top.R, (grid[first - 1], grid[first]), solver='bisect')
    t = top.time(u1, top.u0, u1) + top.time(u1, u1, u_r)
    print('frictionless short dip: u1', mp.nstr(u1, 20), 'u2', mp.nstr(u2, 20), 'R = 0 at u', mp.nstr(u_r, 20),
          'lift-off at:', mp.nstr(t, 20), 's')

if __name__ == '__main__':
    main()
