"""Kalman tracking of the level: the only stage with state, called once per frame.

Constant-velocity model (filterpy ``KalmanFilter``), state ``x = [level, rate]`` in ml and ml/s::

    F = [[1, dt],          x_k = F x_{k-1} + w,  w ~ N(0, Q)
         [0,  1]]
    Q = q * [[dt^4/4, dt^3/2],   white-noise acceleration, q = (accel_div_s2 * division_ml)^2
             [dt^3/2, dt^2  ]]
    H = [[1, 0]]           z_k = H x_k + v,      v ~ N(0, R)
    R = [[sigma_z^2]]      sigma_z: the reading's own sigma (fit residual and edge localisation),
                           never below ``min_sigma_div`` divisions

Every frame calls :meth:`LevelTracker.step` with the frame time and the measurement or None
(the SORT/norfair contract). A measurement whose squared Mahalanobis distance
``y^2 / S`` exceeds ``gate**2`` is an outlier and not fused; if ``reacquire_after``
consecutive outliers agree with each other, the level truly jumped (a fast plunger move, a
new view) and the filter restarts from them. Without a fused measurement the filter coasts:
it predicts, and its sigma grows with Q; after ``coast_limit_s`` it reports ``lost``. A
coasting prediction is reported as the level only while it stays within ``coast_reach_div``
divisions of the last level fused and no measurement since has disagreed with it: a still
level (a hand over it) is held, but a moving one is not carried on past what was seen, for it
may have stopped or turned (at the top of a ramp the prediction ran 9.5 divisions past the
level), and a level the camera saw elsewhere is not held. Nor is a level measured fewer than
``hold_after`` times since the filter started: one measurement says nothing of whether the
level stands still (a burette seen once at its fullest was held for 3 s while it drained,
up to 125 divisions off). The filter goes on predicting
either way, so a measurement that returns is gated against it.

The per-frame history (prior and posterior) is kept so :func:`rts_smooth` can run the
Rauch-Tung-Striebel smoother over a finished recording.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from filterpy.kalman import KalmanFilter

from streamread.errors import ConfigError, expected

TrackState = Literal["calibrating", "tracking", "coasting", "lost"]


@dataclass(frozen=True)
class TrackerConfig:
    """Noise and gating, in scale divisions so one setting suits every apparatus."""

    accel_div_s2: float = 30.0
    min_sigma_div: float = 0.02
    gate: float = 4.0
    reacquire_after: int = 2
    coast_limit_s: float = 3.0
    coast_reach_div: float = 1.0
    hold_after: int = 3  # measurements fused since the filter started before a level is held unseen

    def __post_init__(self) -> None:
        for name in ("accel_div_s2", "min_sigma_div", "gate", "coast_limit_s", "coast_reach_div"):
            if not getattr(self, name) > 0:
                raise ConfigError(expected("tracker", name, "> 0", getattr(self, name)))
        for name in ("reacquire_after", "hold_after"):
            if getattr(self, name) < 1:
                raise ConfigError(expected("tracker", name, ">= 1", getattr(self, name)))


@dataclass(frozen=True)
class TrackEstimate:
    """The filter's answer for one frame. ``level`` is None before the first measurement, when
    lost, and while coasting once the prediction has moved ``coast_reach_div`` from the last
    level fused or a measurement has disagreed with it, or before ``hold_after`` were fused."""

    time_s: float
    level: float | None
    rate: float | None
    sigma: float | None
    state: TrackState
    fused: bool = False
    outlier: bool = False

    def __post_init__(self) -> None:
        if (self.level is None) != (self.sigma is None):
            raise ValueError(expected("estimate", "sigma", "present exactly when level is", self.sigma))


@dataclass
class _Step:
    time_s: float
    x_prior: np.ndarray
    p_prior: np.ndarray
    x_post: np.ndarray
    p_post: np.ndarray
    f: np.ndarray
    restart: bool = False  # the filter started afresh here: the smoother must not cross it


@dataclass
class LevelTracker:
    """Follows the level in ml; ``division_ml`` sets the noise scale."""

    division_ml: float
    config: TrackerConfig = field(default_factory=TrackerConfig)
    keep_history: bool = False  # for the RTS smoother; off in live use so memory stays flat
    _kf: KalmanFilter | None = field(default=None, init=False, repr=False)
    _last_t: float | None = field(default=None, init=False)
    _last_fused_t: float | None = field(default=None, init=False)
    _last_fused_level: float | None = field(default=None, init=False)
    _fused_count: int = field(default=0, init=False)  # measurements behind the filter since it started
    _model_dt: float | None = field(default=None, init=False, repr=False)
    _outliers: list[tuple[float, float, float]] = field(default_factory=list, init=False, repr=False)
    history: list[_Step | None] = field(default_factory=list, init=False, repr=False)

    def __post_init__(self) -> None:
        if not self.division_ml > 0:
            raise ConfigError(expected("tracker", "division_ml", "> 0", self.division_ml))

    # -- model ---------------------------------------------------------------------------------
    def _q(self, dt: float) -> np.ndarray:
        q = (self.config.accel_div_s2 * self.division_ml) ** 2
        return q * np.array([[dt ** 4 / 4, dt ** 3 / 2], [dt ** 3 / 2, dt ** 2]])

    def _start(self, t: float, level: float, sigma: float, rate: float = 0.0, measured: int = 1) -> None:
        kf = KalmanFilter(dim_x=2, dim_z=1)
        kf.x = np.array([[level], [rate]])
        kf.P = np.diag([sigma ** 2, (5 * self.division_ml) ** 2])  # rate unknown: a few divisions/s
        kf.H = np.array([[1.0, 0.0]])
        kf.inv = _inverse_1x1  # S is 1x1: filterpy's hook for the inverse, far cheaper than np.linalg.inv
        self._kf = kf
        self._model_dt = None
        self._last_t = t
        self._last_fused_t = t
        self._last_fused_level = level
        self._fused_count = measured
        self._outliers.clear()

    def reset(self) -> None:
        """Forget the level (a new apparatus or a new view whose scale may differ)."""
        self._kf = None
        self._last_t = None
        self._last_fused_t = None
        self._last_fused_level = None
        self._fused_count = 0
        self._outliers.clear()

    def _remember(self, step: _Step | None) -> None:
        if self.keep_history:
            self.history.append(step)

    @property
    def active(self) -> bool:
        return self._kf is not None

    # -- the per-frame call ------------------------------------------------------------------
    def step(self, t: float, measurement: float | None, sigma: float | None = None,
             calibrated: bool = True) -> TrackEstimate:
        """Advance to time ``t`` (seconds) and fuse ``measurement`` (ml) if it passes the gate."""
        if self._last_t is not None and t < self._last_t:
            raise ValueError(expected("tracker", "t", f">= the previous time {self._last_t}", t))
        floor = self.config.min_sigma_div * self.division_ml
        r = max(floor, sigma if sigma is not None and math.isfinite(sigma) else floor)
        if self._kf is None:
            if measurement is None:
                self._remember(None)
                return TrackEstimate(t, None, None, None, "lost" if calibrated else "calibrating")
            self._start(t, measurement, r)
            assert self._kf is not None
            self._remember(_Step(t, self._kf.x.copy(), self._kf.P.copy(), self._kf.x.copy(),
                                      self._kf.P.copy(), np.eye(2), restart=True))
            return self._estimate(t, "tracking", fused=True)
        kf = self._kf
        dt = max(t - (self._last_t or t), 1e-6)
        self._last_t = t
        if dt != self._model_dt:  # a file's frames come at one rate: build F and Q once
            self._model_dt = dt
            kf.F = np.array([[1.0, dt], [0.0, 1.0]])
            kf.Q = self._q(dt)
        kf.predict()
        prior = (kf.x.copy(), kf.P.copy()) if self.keep_history else None  # only the smoother needs it
        fused = outlier = False
        if measurement is not None:
            kf.R[0, 0] = r * r  # in place: filterpy made R a 1x1 array
            innovation = measurement - float(kf.x[0, 0])
            s = float(kf.P[0, 0]) + r ** 2
            if innovation ** 2 / s <= self.config.gate ** 2:
                kf.update(np.array([[measurement]]))
                fused = True
                self._outliers.clear()
                self._last_fused_t = t
                self._last_fused_level = float(kf.x[0, 0])
                self._fused_count += 1
            else:
                outlier = True
                self._outliers.append((t, measurement, r))
                if self._reacquire():
                    new = self._kf
                    self._remember(_Step(t, new.x.copy(), new.P.copy(), new.x.copy(), new.P.copy(), np.eye(2),
                                              restart=True))
                    return self._estimate(t, "tracking", fused=True, outlier=True)
        if prior is not None:
            self._remember(_Step(t, *prior, kf.x.copy(), kf.P.copy(), kf.F.copy()))
        if fused:
            return self._estimate(t, "tracking", fused=True)
        if self._last_fused_t is not None and t - self._last_fused_t > self.config.coast_limit_s:
            self._kf = None
            self._last_t = t
            return TrackEstimate(t, None, None, None, "lost", outlier=outlier)
        estimate = self._estimate(t, "coasting", outlier=outlier)
        assert estimate.level is not None and self._last_fused_level is not None
        moved = abs(estimate.level - self._last_fused_level)
        if self._outliers or moved > self.config.coast_reach_div * self.division_ml \
                or self._fused_count < self.config.hold_after:
            return TrackEstimate(t, None, None, None, "coasting", outlier=outlier)
        return estimate

    def _reacquire(self) -> bool:
        """Consecutive outliers that agree (within their sigmas plus the motion between them) mean a jump."""
        if len(self._outliers) < self.config.reacquire_after:
            return False
        recent = self._outliers[-self.config.reacquire_after:]
        (t0, z0, r0), (t1, z1, r1) = recent[0], recent[-1]
        rate = (z1 - z0) / max(t1 - t0, 1e-6)
        spread = max(abs(z - (z0 + rate * (t - t0))) for t, z, _ in recent)
        if spread > 3 * max(r0, r1) + 0.5 * self.division_ml:
            return False
        self._start(t1, z1, r1, rate=rate if len(recent) > 1 else 0.0, measured=len(recent))
        return True

    def _estimate(self, t: float, state: TrackState, fused: bool = False, outlier: bool = False) -> TrackEstimate:
        assert self._kf is not None
        x, p = self._kf.x, self._kf.P
        return TrackEstimate(t, float(x[0, 0]), float(x[1, 0]), float(math.sqrt(max(p[0, 0], 0.0))), state,
                             fused=fused, outlier=outlier)


def _inverse_1x1(s: np.ndarray) -> np.ndarray:
    return 1.0 / s


def rts_smooth(history: list[_Step | None]) -> list[tuple[float, float, float] | None]:
    """Rauch-Tung-Striebel smoothing over each uninterrupted run of the history.

    Returns (level, rate, sigma) per frame, None where the filter had no state. Runs are split
    where the filter was restarted.
    """
    out: list[tuple[float, float, float] | None] = [None] * len(history)
    run: list[int] = []

    def flush() -> None:
        if not run:
            return
        xs = [history[i].x_post.copy() for i in run]  # type: ignore[union-attr]
        ps = [history[i].p_post.copy() for i in run]  # type: ignore[union-attr]
        for k in range(len(run) - 2, -1, -1):
            nxt = history[run[k + 1]]
            assert nxt is not None
            gain = ps[k] @ nxt.f.T @ np.linalg.inv(nxt.p_prior)
            xs[k] = xs[k] + gain @ (xs[k + 1] - nxt.x_prior)
            ps[k] = ps[k] + gain @ (ps[k + 1] - nxt.p_prior) @ gain.T
        for k, i in enumerate(run):
            out[i] = (float(xs[k][0, 0]), float(xs[k][1, 0]), float(math.sqrt(max(ps[k][0, 0], 0.0))))
        run.clear()

    for i, step in enumerate(history):
        if step is None:
            flush()
            continue
        if step.restart:
            flush()
        run.append(i)
    flush()
    return out
