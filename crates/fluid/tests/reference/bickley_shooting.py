"""Independent growth rates of the Bickley jet U = sech^2 y between walls at
y = -8 and 8, for the regression test `the_bickley_jet_sinuous_mode_is_found`
(crates/fluid/src/analysis/instability.rs). Needs numpy and scipy.

Rayleigh's equation (U - c)(phi'' - k^2 phi) - U'' phi = 0, phi(-8) = 0, is
regular for Im c > 0: integrate phi'' = (k^2 + U''/(U - c)) phi from y = -8
(phi = 0, phi' = 1) to y = 0 with DOP853 (rtol 1e-13), and solve
phi'(0) = 0 (the sinuous mode is even) for complex c by the secant method.
The Wronskian match at y = 0 with the solution from y = +8 gives the same c
to every printed digit, and rtol 1e-10, 1e-12, 1e-13 agree to 1e-12.
A second-order finite-difference generalised eigenproblem on 1024, 2048,
4096 intervals gives k Im c = 0.0220997, 0.02209219, 0.02209203 at k = 1.9.

Output (numpy 2.4.6, scipy 1.17.1):
k 1.9   c = 0.6496547050780082+0.011627338319323938j  k Im c = 2.2091942807e-02
k 1.95  c = 0.6581965386199845+0.00567832877183954j   k Im c = 1.1072741105e-02
k 1.99  c = 0.664978389930108+0.0011138705081814519j  k Im c = 2.2166023113e-03
k 1.995 c = 0.6658228888684506+0.0005555689964194465j k Im c = 1.1083601479e-03
k 1.5   c = 0.5783685801295467+0.06848943624856109j   k Im c = 1.0273415437e-01
k 1.0   c = 0.47513631767641135+0.15898795836715465j  k Im c = 1.5898795837e-01
k 1.999 c = 0.6664979688529267+0.00011089507423215502j k Im c = 2.2167925339e-04
"""
import numpy as np
from scipy.integrate import solve_ivp

L = 8.0
U = lambda y: 1 / np.cosh(y) ** 2
Upp = lambda y: (4 * np.sinh(y) ** 2 - 2) / np.cosh(y) ** 4  # (sech^2)''


def shoot(c, k, a=-L, b=0.0, rtol=1e-13):
    f = lambda y, z: [z[1], (k * k + Upp(y) / (U(y) - c)) * z[0]]
    s = solve_ivp(f, (a, b), [0j, 1 + 0j], method="DOP853", rtol=rtol, atol=1e-300)
    return s.y[:, -1]


def solve(k, c0, rtol=1e-13):
    def F(c):
        p, dp = shoot(c, k, rtol=rtol)
        return dp / p

    c1, c2 = c0, c0 * (1 + 1e-4) + 1e-5j
    f1, f2 = F(c1), F(c2)
    for _ in range(60):
        c1, c2 = c2, c2 - f2 * (c2 - c1) / (f2 - f1)
        f1, f2 = f2, F(c2)
        if abs(c2 - c1) < 1e-14:
            break
    return c2


if __name__ == "__main__":
    for k, c0 in [(1.9, 0.65 + 0.0116j), (1.95, 0.658 + 0.0057j), (1.99, 0.665 + 0.0011j),
                  (1.995, 0.6658 + 0.00055j), (1.5, 0.578 + 0.068j), (1.0, 0.475 + 0.159j),
                  (1.999, 0.6665 + 0.00011j)]:
        c = solve(k, c0)
        print("k", k, "c =", c, "k Im c = %.10e" % (k * c.imag))
