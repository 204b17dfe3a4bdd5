r"""A nonlinear control problem solved in float64, for the evidence of D3 and D4.

:class:`NonlinearFamily` is written from the definitions with NumPy and SciPy (never symrb): its
implicit advance map :math:`(x_k, p_k) \mapsto (x_{k+1}, p_{k+1})`, the Jacobian of that map by
implicit differentiation and by central differences, and the second derivatives of the reduced
and of the frozen-control Hamiltonian.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import root


class NonlinearFamily:
    """f(x, u) = x + tau tanh(W x + B u + c), g(x, u) = |u|^2/2 + alpha |x|^2/2 (float64).

    The implicit advance map solves p_k = H_x(y, x_k, u) and H_u(y, x_k, u) = 0 for (y, u) with
    scipy.optimize.root (analytic Jacobian), then x_{k+1} = f(x_k, u); its Jacobian follows by
    implicit differentiation.  Written from the definitions with NumPy (an independent route).
    """

    def __init__(self, nx: int, nu: int, seed: int, tau: float = 0.3, alpha: float = 0.5) -> None:
        rng = np.random.default_rng(seed)
        self.nx, self.nu, self.tau, self.alpha = nx, nu, tau, alpha
        self.W = rng.standard_normal((nx, nx))
        self.B = rng.standard_normal((nx, nu))
        self.c = rng.standard_normal(nx)

    def f(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        return x + self.tau * np.tanh(self.W @ x + self.B @ u + self.c)

    def _parts(self, x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.tanh(self.W @ x + self.B @ u + self.c)
        d = 1.0 - t**2
        return d, -2.0 * t * d

    def equations(self, x: np.ndarray, p: np.ndarray, y: np.ndarray, u: np.ndarray):
        """Residual of (p_k = H_x, 0 = H_u) and its Jacobians in (y, u), x and p."""
        d, dd = self._parts(x, u)
        tau, W, B = self.tau, self.W, self.B
        F = np.concatenate([y + tau * W.T @ (d * y) - self.alpha * x - p, tau * B.T @ (d * y) - u])
        Jy = np.vstack([np.eye(self.nx) + tau * W.T * d, tau * B.T * d])
        Ju = np.vstack([tau * W.T @ np.diag(y * dd) @ B, tau * B.T @ np.diag(y * dd) @ B])
        Ju[self.nx :] -= np.eye(self.nu)
        Jx = np.vstack([
            tau * W.T @ np.diag(y * dd) @ W - self.alpha * np.eye(self.nx),
            tau * B.T @ np.diag(y * dd) @ W,
        ])  # fmt: skip
        Jp = np.vstack([-np.eye(self.nx), np.zeros((self.nu, self.nx))])
        return F, np.hstack([Jy, Ju]), Jx, Jp

    def reduced_hessian_blocks(self, x: np.ndarray, y: np.ndarray, u: np.ndarray):
        """Second derivatives of H*(y, x) = H(y, x, u*(y, x)) by the Schur complement
        H*_ab = H_ab - H_au H_uu^{-1} H_ub: (H*_xx, H*_xy, H*_yy), (H*_xy)_ij = d2/dx_i dy_j."""
        d, dd = self._parts(x, u)
        tau, W, B = self.tau, self.W, self.B
        Hxx = tau * W.T @ np.diag(y * dd) @ W - self.alpha * np.eye(self.nx)
        Hxy = (np.eye(self.nx) + tau * d[:, None] * W).T
        Huu = tau * B.T @ np.diag(y * dd) @ B - np.eye(self.nu)
        Hux = tau * B.T @ np.diag(y * dd) @ W
        Huy = tau * B.T * d
        S = np.linalg.solve(Huu, np.hstack([Hux, Huy]))
        Sx, Sy = S[:, : self.nx], S[:, self.nx :]
        return Hxx - Hux.T @ Sx, Hxy - Hux.T @ Sy, -Huy.T @ Sy

    def frozen_hessian_blocks(self, x: np.ndarray, y: np.ndarray, u: np.ndarray):
        """Second derivatives of Hhat with the control held at u*: (H_xx, H_xy, H_yy = 0)."""
        d, dd = self._parts(x, u)
        Hxx = self.tau * self.W.T @ np.diag(y * dd) @ self.W - self.alpha * np.eye(self.nx)
        Hxy = (np.eye(self.nx) + self.tau * d[:, None] * self.W).T
        return Hxx, Hxy, np.zeros((self.nx, self.nx))

    def advance(self, x: np.ndarray, p: np.ndarray, guess: np.ndarray | None = None):
        """(x_{k+1}, p_{k+1}, u_k) from (x_k, p_k) by solving the implicit step."""
        nx = self.nx
        z0 = np.concatenate([p, np.zeros(self.nu)]) if guess is None else guess

        def fun(zz: np.ndarray):
            F, J, _, _ = self.equations(x, p, zz[:nx], zz[nx:])
            return F, J

        sol = root(fun, z0, jac=True, method="hybr", options={"xtol": 1e-14})
        y, u = sol.x[:nx], sol.x[nx:]
        F, _, _, _ = self.equations(x, p, y, u)
        if not np.max(np.abs(F)) <= 1e-12:  # hybr may flag xtol as unmet at round-off
            raise RuntimeError(f"implicit step did not converge: |F| = {np.max(np.abs(F)):.2e}")
        return self.f(x, u), y, u

    def advance_jacobian(self, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Jacobian of (x_k, p_k) -> (x_{k+1}, p_{k+1}) by implicit differentiation."""
        nx = self.nx
        _x1, y, u = self.advance(x, p)
        _F, Jyu, Jx, Jp = self.equations(x, p, y, u)
        dyu = -np.linalg.solve(Jyu, np.hstack([Jx, Jp]))
        d, _ = self._parts(x, u)
        fx = np.eye(nx) + self.tau * d[:, None] * self.W
        fu = self.tau * d[:, None] * self.B
        dx1 = np.hstack([fx, np.zeros((nx, nx))]) + fu @ dyu[nx:]
        return np.vstack([dx1, dyu[:nx]])

    def advance_jacobian_fd(self, x: np.ndarray, p: np.ndarray, step: float = 1e-6) -> np.ndarray:
        """Central finite-difference Jacobian (each perturbed solve starts from the base point)."""
        nx = self.nx
        _x1, y, u = self.advance(x, p)
        guess = np.concatenate([y, u])
        z = np.concatenate([x, p])
        cols = []
        for j in range(2 * nx):
            e = np.zeros(2 * nx)
            e[j] = step
            a1, b1, _ = self.advance((z + e)[:nx], (z + e)[nx:], guess)
            a2, b2, _ = self.advance((z - e)[:nx], (z - e)[nx:], guess)
            cols.append((np.concatenate([a1, b1]) - np.concatenate([a2, b2])) / (2 * step))
        return np.array(cols).T
