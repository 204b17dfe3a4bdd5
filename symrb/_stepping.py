"""The machinery of the paper's discrete maps (:mod:`symrb.paper`): validation of the
step arguments, the warm-started solver of :math:`J_D(U) = M` and the bookkeeping of a run."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _validate as v
from ._progress import progress_bar
from ._results import DiscreteFlowSolution, Trajectory, step_failure
from ._validate import Array
from .errors import InputError, SymrbError
from .solvers import _EPS, _condition, _fold_scale_one, _solve_batch, _warm_single

_MAXITER = 30


def _check_steps(steps: int, save_every: int) -> tuple[int, int]:
    return v.count(steps, "steps", 0), v.count(save_every, "save_every", 1)


def _check_h(h: float) -> float:
    value = v.real_scalar(h, "h")
    if not value > 0:
        raise InputError(f"h must be a finite number > 0, got {h!r}; pass a float > 0")
    return value


class _Stepper:
    """Solves J_D(U) = M on a flat batch, warm-starting from the previous solution.

    After each solve ``last_iterations``, ``last_residual``, ``last_tol`` (and, with
    ``diagnostics``, ``last_condition``) describe it.
    """

    def __init__(self, lam: Array, batch: tuple[int, ...], diagnostics: bool = False) -> None:
        nn = lam.shape[-1]
        self.lam = np.broadcast_to(lam, batch + (nn,)).reshape(-1, nn)
        self.U: Array | None = None
        self.U_prev: Array | None = None
        self.diagnostics = diagnostics
        self.last_iterations = 0  # Newton iterations of the last solve (summed over the batch)
        self.last_residual = 0.0
        self.last_tol = 0.0
        self.last_condition = float("nan")

    def _record(self, U: Array, res: Array, tol: Array) -> None:
        if res.size:
            i = int(np.argmax(res / np.where(tol > 0, tol, 1.0)))
            self.last_residual, self.last_tol = float(res[i]), float(tol[i])
        if self.diagnostics and U.shape[0]:
            self.last_condition = float(np.max(_condition(U, self.lam)))

    def solve(self, M: Array) -> Array:
        Mf = M.reshape(self.lam.shape[0], *M.shape[-2:])
        Mf = 0.5 * (Mf - np.swapaxes(Mf, -1, -2))  # rounding leaves M skew only to ~eps
        tol = 10.0 * _EPS * np.sqrt(np.einsum("bij,bij->b", Mf, Mf))
        if self.U is not None and Mf.shape[0] == 1:
            guess = self.U[0]
            if self.U_prev is not None:
                # U changes smoothly along a run: extrapolate U_k (U_{k-1}^T U_k) (orthogonal)
                guess = guess @ (self.U_prev[0].T @ guess)
                # one Newton-Schulz step back to SO(n), so rounding errors in U^T U - I do not
                # compound from step to step
                guess = guess @ (1.5 * np.eye(guess.shape[-1]) - 0.5 * (guess.T @ guess))
            got = _warm_single(guess, Mf[0], self.lam[0], float(tol[0]), _MAXITER, True)
            if got is not None:
                self.U_prev = self.U
                self.U = got[0][None]
                self.last_iterations = got[1]
                self._record(self.U, np.array([got[2]]), np.array([got[3]]))
                return got[0].reshape(M.shape)
        U, it, res, _margin, _start, tol = _solve_batch(
            Mf, self.lam, tol, _MAXITER, self.U, floor=True
        )
        self.U_prev, self.U = self.U, U
        self.last_iterations = int(it.sum())
        self._record(U, res, tol)
        return U.reshape(M.shape)

    def fold(self, M: Array, exc: Exception | None = None) -> float | None:
        """The smallest fold_scale over the batch of M (for the failure report); None after a
        failure of the arithmetic (``exc`` not a symrb error), or for M that is not finite."""
        if (exc is not None and not isinstance(exc, SymrbError)) or not np.isfinite(M).all():
            return None
        Mf = M.reshape(self.lam.shape[0], *M.shape[-2:])
        Mf = 0.5 * (Mf - np.swapaxes(Mf, -1, -2))
        return min(
            (_fold_scale_one(Mf[i], self.lam[i]) for i in range(Mf.shape[0])), default=np.inf
        )


def _prepare(
    lam: ArrayLike, *mats: tuple[ArrayLike, str, str]
) -> tuple[Array, list[Array], tuple[int, ...]]:
    L = v.inertia(lam, positive=True)
    nn = L.shape[-1]
    arrays = []
    for x, name, kind in mats:
        if kind == "SO":
            arrays.append(v.orthogonal(x, name, nn))
        elif kind == "skew":
            arrays.append(v.skew(x, name, nn))
        else:
            arrays.append(v.square(x, name, nn))
        v.bounded(arrays[-1], name)
    try:
        batch = np.broadcast_shapes(L.shape[:-1], *[a.shape[:-2] for a in arrays])
    except ValueError:
        shapes = ", ".join(
            f"{name} {a.shape}" for (_x, name, _k), a in zip(mats, arrays, strict=True)
        )
        raise InputError(
            f"the batch axes do not broadcast: lam {L.shape}, {shapes}; pass arrays whose "
            "leading axes broadcast (numpy rules)"
        ) from None
    arrays = [np.broadcast_to(a, batch + (nn, nn)).copy() for a in arrays]
    return L, arrays, batch


def _failure(
    k: int, steps: int, reason: str, fold: float | None, h: float | None
) -> tuple[str, float | None]:
    """The message of a failed step ``k`` (``reason`` why; ``fold`` the fold scale of its
    momentum, ``h`` the time step of a flow that has one) and ``h_max`` (None without ``h``)."""
    note, h_max = "", None
    if fold is not None and np.isfinite(fold):
        if fold <= 1.0:
            note = f" (the step's momentum is {(1.0 / fold - 1.0) * 100:.4g} % past the fold"
            if h is not None:
                h_max = fold * h
                note += (
                    f"; h = {h:.10g}, the largest step that works there is just below "
                    f"h_max = {h_max:.10g})"
                )
            else:
                note += f"; the momentum scaled by less than {fold:.10g} works)"
        else:
            note = f" (the step's momentum is inside the fold by {(1.0 - 1.0 / fold) * 100:.4g} %)"
    return f"step {k} of {steps} failed: {reason}{note}", h_max


def _engine_result(
    sol: DiscreteFlowSolution,
    y: dict[str, Array],
    k: NDArray[np.int64],
    *,
    method: str,
    h: float | None,
    steps: int,
    iterations: NDArray[np.int64] | None = None,
) -> DiscreteFlowSolution:
    """A paper map's result from the successful :func:`symrb.engine.mv_flow` run ``sol`` that
    computed it (``steps`` of the paper's map): the states ``y`` at the steps ``k`` (a run that fails on the engine is redone by
    the reference loop, which reports the failure).  The engine checks each solve against its
    own tolerance but reports no residual: ``residual``, ``tol`` and ``condition`` are empty."""
    return DiscreteFlowSolution(
        t=k.astype(np.float64) * (1.0 if h is None else h),
        k=k,
        y=Trajectory(y),
        iterations=sol.iterations if iterations is None else iterations,
        success=sol.success,
        status=sol.status,
        message=f"all {steps} steps taken",
        method=method,
        h=h,
    )


class _Run:
    """Bookkeeping of a discrete run: saved states, Newton counts, failure, progress bar."""

    def __init__(self, steps: int, solves: int, method: str, progress: bool) -> None:
        self.steps, self.method = steps, method
        self.saved: dict[str, list[Array]] = {}
        self.k: list[int] = []
        self.iterations = np.zeros(solves, dtype=np.int64)
        self.residual = np.zeros(solves)
        self.tol = np.zeros(solves)
        self.condition = np.full(solves, np.nan)
        self.solves = 0
        self.failure = ""
        self.failed_step: int | None = None
        self.fold: float | None = None
        self.h_max: float | None = None
        self.halvings: list[int] = []
        self.bar = progress_bar(steps, method, progress)

    def save(self, k: int, **states: Array) -> None:
        self.k.append(k)
        for name, x in states.items():
            self.saved.setdefault(name, []).append(x)

    def count(self, stepper: _Stepper) -> None:
        if self.solves == self.iterations.shape[0]:  # halved steps solve more often
            grow = max(16, self.solves)
            self.iterations = np.concatenate([self.iterations, np.zeros(grow, dtype=np.int64)])
            self.residual = np.concatenate([self.residual, np.zeros(grow)])
            self.tol = np.concatenate([self.tol, np.zeros(grow)])
            self.condition = np.concatenate([self.condition, np.full(grow, np.nan)])
        i = self.solves
        self.iterations[i] = stepper.last_iterations
        self.residual[i], self.tol[i] = stepper.last_residual, stepper.last_tol
        self.condition[i] = stepper.last_condition
        self.solves += 1

    def fail(
        self, k: int, exc: Exception, fold: float | None = None, h: float | None = None
    ) -> None:
        self.failed_step, self.fold = k, fold
        self.failure, self.h_max = _failure(k, self.steps, step_failure(exc), fold, h)

    def result(self, t_scale: float | None) -> DiscreteFlowSolution:
        self.bar.close()
        k = np.asarray(self.k, dtype=np.int64)
        y = Trajectory({name: np.stack(xs) for name, xs in self.saved.items()})
        t = k.astype(np.float64) * (1.0 if t_scale is None else t_scale)
        halved = sum(1 for j in self.halvings if j)
        message = self.failure or f"all {self.steps} steps taken"
        if halved:
            message += (
                f"; {halved} step(s) halved (at most {max(self.halvings)} times) to stay inside "
                "the fold of J_D"
            )
        n = self.solves
        return DiscreteFlowSolution(
            t=t,
            k=k,
            y=y,
            iterations=self.iterations[:n],
            success=not self.failure,
            status=-1 if self.failure else 0,
            message=message,
            method=self.method,
            h=t_scale,
            residual=self.residual[:n],
            tol=self.tol[:n],
            condition=self.condition[:n],
            failed_step=self.failed_step,
            fold=self.fold,
            h_max=self.h_max,
            halvings=np.asarray(self.halvings, dtype=np.int64),
        )
