r"""Every solution of :math:`U\Lambda - \Lambda U^T = M` in :math:`O(n)`, found independently.

Used by D7 (the equation for :math:`U_k` has several solutions), D8 and D10 (the fold): an
enumeration of the invariant subspaces of a Hamiltonian matrix, written with NumPy only.
"""

from __future__ import annotations

import itertools

import numpy as np

from derivations import reference as ref


def _all_jd_solutions(M_: np.ndarray, lam: np.ndarray) -> list[np.ndarray]:
    r"""Every :math:`U\in O(n)` with :math:`U\Lambda - \Lambda U^T = M` (an independent route).

    With :math:`X = U\Lambda = S + M/2` the equation is the Riccati equation
    :math:`S^2 + (SM - MS)/2 - \Lambda^2 - M^2/4 = 0` for a real symmetric S; its solutions are
    :math:`S = X_2X_1^{-1}` for the n-dimensional invariant subspaces :math:`[X_1; X_2]` of
    :math:`H = \begin{pmatrix}-M/2 & -I\\ -\Lambda^2 - M^2/4 & -M/2\end{pmatrix}`.  For H with
    distinct eigenvalues these are spanned by n eigenvectors, so trying every choice of n of the
    2n eigenvectors finds every solution.  Kept: real symmetric S whose U solves the equation to
    1e-12 (distinct to 1e-8).
    """
    nn = len(lam)
    eye = np.eye(nn)
    C = np.diag(lam**2) + M_ @ M_ / 4
    H = np.block([[-M_ / 2, -eye], [-C, -M_ / 2]])
    _w, V = np.linalg.eig(H)
    found: list[np.ndarray] = []
    for idx in itertools.combinations(range(2 * nn), nn):
        X1, X2 = V[:nn, list(idx)], V[nn:, list(idx)]
        if np.linalg.cond(X1) > 1e10:
            continue
        S = X2 @ np.linalg.inv(X1)
        if np.abs(S.imag).max() > 1e-9 or np.abs(S - S.T).max() > 1e-9:
            continue
        Ux = (S.real + M_ / 2) / lam[None, :]
        err = np.abs(ref.J_D(Ux, lam) - M_).max() + np.abs(Ux.T @ Ux - eye).max()
        if err <= 1e-12 and not any(np.abs(Ux - V2).max() < 1e-8 for V2 in found):
            found.append(Ux)
    return found


def _on_branch(Ux: np.ndarray, lam: np.ndarray) -> bool:
    """Every eigenvalue of U Lambda in the open right half-plane (the branch through I)."""
    return bool(np.linalg.eigvals(Ux * lam[None, :]).real.min() > 0)
