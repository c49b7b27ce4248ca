"""The fast engine: the same stepgen, servo period by servo period, with numpy for the pulses.

Between two update-freq calls the base thread's behaviour is deterministic. In the common case
(no DDS hold, no sign change of ``addval``, ``curr_dir`` already agreeing with the sign of
``addval``, |addval| ≤ 2^28) it has a closed form:

* addval in the i-th period of the chunk is ``a0 + sgn·min(i·deltalim, |target − a0|)``
  (a jump straight to the target when deltalim is 0), so the accumulator at the chunk's end is
  an arithmetic series (pass 1, pure Python integers, O(1) per servo period);
* ``accum`` moves one way by at most one step a period, so a step is where ``accum`` first
  reaches the next multiple of 2^28 (the same bit-28 change as the C): pass 2 solves the
  series for it, for every step at once with numpy, and works from the steps, never period by
  period: STEP is high for ceil(steplen/P) periods from each step (timer1), DIR is constant,
  and the phase state moves by ±1 at each step.

Every other servo period ("exact chunk": a reversal, a hold, a timer interaction at the start,
the first steps) is run through the reference make-pulses of :mod:`stepgen.reference`, one period
at a time, with the timers made concrete first. The timers of the fast chunks are kept lazily:
only the last step's invocation is needed, and only when an exact chunk follows.

``tests/stepgen/test_fast.py`` checks with hypothesis that this engine and
:func:`stepgen.reference.run_reference` give identical toggles, counts and final state.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from stepgen.reference import (
    HALF_STEP,
    ONE_STEP,
    PICKOFF,
    Channel,
    Component,
    InvocationRun,
    StepgenConfig,
    final_state,
    follow_position,
    follow_velocity,
    make_pulses_channel,
    update_schedule,
)
from wavecheck.progress import current
from wavecheck.steptypes import StepType

__all__ = ["run_fast"]

_DESC = 9  #: numbers describing a chunk for pass 2
_STEPS_BLOCK = 1 << 14  #: steps of fast chunks solved at a time in pass 2
_TRACK = True  #: pass 1 runs settled position-mode stretches through :func:`_track`

#: A fast chunk that stepped, whose last step is found only when an exact chunk follows:
#: (k0, m, accum0, a0, sgn, d_eff, span, counts at its end, (timer1, timer2, timer3) loads).
_Pending = tuple[int, int, int, int, int, int, int, int, tuple[int, int, int]]


def _last_step(p: _Pending) -> int:
    """Invocation index of the last step of a pending fast chunk (binary search, O(log m))."""
    k0, m, accum0, a0, sgn, d_eff, span, count_end, _ = p
    full = span // d_eff if d_eff else 0
    lo, hi = 1, m  # first i with count(i) == count_end; exists because the count changed
    while lo < hi:
        mid = (lo + hi) // 2
        if (accum0 + int(_addval_sum(mid, a0, sgn, d_eff, span, full))) >> PICKOFF == count_end:
            hi = mid
        else:
            lo = mid + 1
    return k0 + lo - 1


def _steady(comp: Component, ch: Channel, base: int, servo: int) -> bool:
    """True once update-freq has nothing left to re-round or rescale (periods and params settled)."""
    return (
        comp.periodns == base
        and comp.old_periodns == base
        and comp.old_dtns == servo
        and ch.old_scale == ch.pos_scale
        and ch.step_len == ch.old_step_len
        and ch.step_space == ch.old_step_space
        and ch.dir_setup == ch.old_dir_setup
        and ch.dir_hold_dly == ch.old_dir_hold_dly
        and ch.enable
    )


def run_fast(
    config: StepgenConfig,
    commands: Sequence[float] | np.ndarray,
    n_periods: int,
) -> InvocationRun:
    """Same contract and result as :func:`stepgen.reference.run_reference`, much faster.

    Pass 1 keeps the channel state in local variables. Until update-freq has settled (the first
    one or two calls re-round the timing params, §3) it calls the reference update-freq; after
    that it runs the same code inlined (steps 5–9 of §4 with nothing left to re-round). Once
    the clamps' limits have settled too, position mode runs in :func:`_track` (the follower
    and the closed form only, nothing else per servo period) for as long as the chunks stay
    fast.
    """
    config.validate()
    kind = config.kind()
    comp = Component([config])
    ch = comp.channels[0]
    base = config.base_period_ns
    servo = config.servo_ns
    cmds = np.asarray(commands, dtype=float)
    n_cmd = len(cmds)
    schedule = update_schedule(config, n_periods)
    bounds = ([0] if (not schedule or schedule[0] != 0) else []) + schedule + [n_periods]
    first_update_at = 0 if schedule and schedule[0] == 0 else 1

    # per-chunk descriptors for pass 2, _DESC numbers each: k0, m, a0, sgn, d_eff, span, dir,
    # step_len, accum0
    desc: list[int] = []
    blocks: list[np.ndarray] = []  # descriptor columns of the chunks before those in ``desc``
    n_blocked = 0  # chunks in ``blocks``
    exact: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    # lazy timers: values after invocation t_ref, or a pending fast chunk
    t_ref = -1
    t_vals = (0, 0, 0)
    pending: _Pending | None = None
    steps_total = 0
    u = 0
    pos_mode = ch.pos_mode
    cycle = max(kind.cycle, 1)
    phased = kind.kind == "phases"
    describe = desc.extend
    steady = False
    limits: tuple[float, float] | None = None  # (max_freq, max_ac) once the clamps settle

    # the channel state, as locals (synced with ``ch`` around reference calls)
    accum = ch.accum
    addval = ch.addval
    target = ch.target_addval
    deltalim = ch.deltalim
    freq = ch.freq
    old_pos_cmd = ch.old_pos_cmd
    curr_dir = ch.curr_dir
    state = ch.state
    maxvel = ch.maxvel
    maxaccel = ch.maxaccel
    # constants once steady
    abs_scale = pos_scale = min_step_period = 0.0
    dt = recip_dt = freqscale = accelscale = 0.0

    def to_ch() -> None:
        ch.accum, ch.addval, ch.target_addval, ch.deltalim = accum, addval, target, deltalim
        ch.freq, ch.old_pos_cmd, ch.curr_dir, ch.state = freq, old_pos_cmd, curr_dir, state
        ch.maxvel, ch.maxaccel = maxvel, maxaccel
        ch.rawcount = accum >> PICKOFF

    report = current()
    n_chunks = len(bounds) - 1
    lengths: list[int] = []  # the chunks' periods, for _track
    ci = 0
    while ci < n_chunks:
        k0, k1 = bounds[ci], bounds[ci + 1]
        if not ci & 1023:
            report(k0, n_periods)
        if k1 <= k0:
            ci += 1
            continue
        updated = False  # update-freq already run for chunk ci (by _track)
        if (
            _TRACK
            and limits is not None  # (then steady)
            and pos_mode
            and n_cmd
            and ci >= first_update_at
            and not ch.hold_dds
            and ch.enable
            and int(limits[1] * accelscale)
        ):
            if not lengths:
                lengths = np.diff(bounds).tolist()
            stop = min(n_chunks, (ci | 1023) + 1)
            # this run's position commands in steps (value · pos_scale, as update-freq
            # multiplies), the last one held; made per run, so few float objects live at once
            pos_list = (cmds[u : u + stop - ci] * pos_scale).tolist()
            pos_list += (cmds[-1:] * pos_scale).tolist() * (stop - ci - len(pos_list))
            deltalim = int(limits[1] * accelscale)
            rec: tuple[list[int], list[int]] = ([], [])
            accum0 = accum
            ci1, u, accum, addval, freq, old_pos_cmd, target, updated = _track(
                lengths, ci, stop, pos_list, u,
                (accum, addval, freq, old_pos_cmd, target, curr_dir),
                (limits[0], limits[1], dt, recip_dt, freqscale, deltalim), rec,
            )  # fmt: skip
            if ci1 > ci:
                if desc:
                    blocks.append(_columns(desc))
                    n_blocked += len(desc) // _DESC
                    desc.clear()
                block, moved, last = _tracked(
                    bounds, ci, ci1, rec, accum0, accum, deltalim, curr_dir, ch
                )
                blocks.append(block)
                n_blocked += ci1 - ci
                steps_total += abs(moved)
                if last is not None:
                    pending = last
                if phased:
                    state = (state + moved) % cycle
                ci = ci1
            if not updated:
                continue
            k0, k1 = bounds[ci], bounds[ci + 1]
        if ci >= first_update_at and not updated:
            value = float(cmds[u if u < n_cmd else n_cmd - 1]) if n_cmd else 0.0
            u += 1
            if steady:
                # ---- update-freq, steps 5-9 of §4, inlined (same operations as the model) ----
                # the clamps, evaluated until one evaluation leaves maxvel and maxaccel as they
                # were: from then on they give the same limits every period
                if limits is None:
                    was = (maxvel, maxaccel)
                    max_freq = 1.0 / (min_step_period * 0.000000001)
                    if maxvel <= 0.0:
                        maxvel = 0.0
                    else:
                        desired_freq = maxvel * abs_scale
                        if desired_freq > max_freq:
                            if not ch.printed_error:
                                to_ch()
                                ch.pos_cmd = ch.vel_cmd = value
                                comp.update_freq(servo)  # the model prints its warning
                                raise AssertionError("unreachable: maxvel clamp after settling")
                            maxvel = max_freq / abs_scale
                        else:
                            max_freq = desired_freq
                    max_ac = max_freq * recip_dt
                    if maxaccel <= 0.0:
                        maxaccel = 0.0
                    elif maxaccel * abs_scale > max_ac:
                        maxaccel = max_ac / abs_scale
                    else:
                        max_ac = maxaccel * abs_scale
                    if was == (maxvel, maxaccel):
                        limits = (max_freq, max_ac)
                else:
                    max_freq, max_ac = limits
                if pos_mode:
                    pos_cmd = value * pos_scale
                    new_vel = follow_position(
                        pos_cmd, old_pos_cmd, accum, freq, max_freq, max_ac, dt, recip_dt
                    )
                    old_pos_cmd = pos_cmd
                else:
                    new_vel = follow_velocity(value * pos_scale, freq, max_freq, max_ac, dt)
                freq = new_vel
                target = int(freq * freqscale)
                deltalim = int(max_ac * accelscale)
            else:
                to_ch()
                if pos_mode:
                    ch.pos_cmd = value
                else:
                    ch.vel_cmd = value
                if k0 > 0:
                    comp.periodns = base
                comp.update_freq(servo)
                freq, old_pos_cmd = ch.freq, ch.old_pos_cmd
                target, deltalim, addval = ch.target_addval, ch.deltalim, ch.addval
                maxvel, maxaccel = ch.maxvel, ch.maxaccel
                steady = _steady(comp, ch, base, servo)
                if steady:
                    pos_scale = ch.pos_scale
                    abs_scale = abs(pos_scale)
                    min_step_period = float(ch.step_len + ch.step_space)
                    dt, recip_dt = comp.dt, comp.recip_dt
                    freqscale, accelscale = comp.freqscale, comp.accelscale
        m = k1 - k0
        a0 = addval
        if target >= a0:
            sgn = 1
            span = target - a0
        else:
            sgn = -1
            span = a0 - target
        d_eff = deltalim if deltalim != 0 else span
        # the chunk's closed form: addval_i = a0 + sgn*min(i*d_eff, span), i = 1..m
        if d_eff == 0:
            a_end = a0
            total = m * a0
        else:
            full = span // d_eff
            if m <= full:
                a_end = a0 + sgn * m * d_eff
                total = m * a0 + sgn * d_eff * (m * (m + 1) // 2)
            else:
                a_end = target
                total = m * a0 + sgn * (d_eff * (full * (full + 1) // 2) + span * (m - full))
        cls = a0 >= 0
        if (
            not ch.hold_dds
            and ch.enable
            and (a_end >= 0) == cls
            and -ONE_STEP <= a0 <= ONE_STEP
            and -ONE_STEP <= a_end <= ONE_STEP
            and (curr_dir == (1 if cls else -1) or (a0 == 0 and a_end == 0))
        ):
            step_len = ch.step_len
            describe((k0, m, a0, sgn, d_eff, span, curr_dir, step_len, accum))
            accum1 = accum + total
            count1 = accum1 >> PICKOFF
            delta = count1 - (accum >> PICKOFF)
            if delta:
                steps_total += delta if delta > 0 else -delta
                hold = step_len + ch.dir_hold_dly
                pending = (
                    k0, m, accum, a0, sgn, d_eff, span, count1,
                    (step_len, hold, hold + ch.dir_setup),
                )  # fmt: skip
                if phased:
                    state = (state + delta) % cycle
            accum = accum1
            addval = a_end
            ci += 1
            continue
        # exact chunk: make the timers concrete, then run the reference make-pulses
        describe((k0, m, a0, sgn, d_eff, span, curr_dir, ch.step_len, accum))
        if pending is not None:
            t_ref = _last_step(pending)
            t_vals = pending[8]
            pending = None
        elapsed = (k0 - 1 - t_ref) * base
        ch.timer1 = max(t_vals[0] - elapsed, 0)
        ch.timer2 = max(t_vals[1] - elapsed, 0)
        ch.timer3 = max(t_vals[2] - elapsed, 0)
        to_ch()
        inc = np.empty(m, dtype=np.int64)
        dirs = np.empty(m, dtype=np.int64)
        comp.periodns = base
        for i in range(m):
            before = ch.accum
            if make_pulses_channel(ch, base):
                steps_total += 1
            inc[i] = ch.accum - before
            dirs[i] = ch.curr_dir
        exact[n_blocked + len(desc) // _DESC - 1] = (inc, dirs)
        accum, addval, curr_dir, state = ch.accum, ch.addval, ch.curr_dir, ch.state
        # timers after this chunk, relative to its last invocation
        t_vals = (ch.timer1, ch.timer2, ch.timer3)
        t_ref = k1 - 1
        ci += 1

    to_ch()
    cols = np.concatenate([*blocks, _columns(desc)], axis=1)
    toggles, counts_at, counts_val = _pass2(kind, base, n_periods, cols, exact)
    run = InvocationRun(
        config=config,
        n_periods=n_periods,
        pins=kind.outputs,
        toggles=toggles,
        counts_at=counts_at,
        counts_val=counts_val,
        steps=steps_total,
        fast_chunks=cols.shape[1] - len(exact),
        exact_chunks=len(exact),
    )
    run.final = final_state(comp)
    run.warnings = list(ch.warnings)
    return run


def _columns(desc: list[int]) -> np.ndarray:
    """The descriptors ``desc`` (``_DESC`` numbers a chunk) as columns: one row per number."""
    return np.fromiter(desc, dtype=np.int64, count=len(desc)).reshape(-1, _DESC).T


def _track(
    lengths: list[int],
    ci: int,
    stop: int,
    pos_list: list[float],
    u: int,
    st: tuple[int, int, float, float, int, int],
    consts: tuple[float, float, float, float, float, int],
    rec: tuple[list[int], list[int]],
) -> tuple[int, int, int, int, float, float, int, bool]:
    """Pass 1 over settled position-mode chunks ``ci`` … ``stop − 1`` while each is fast.

    The same update-freq as the general loop (:func:`stepgen.reference.follow_position`
    inlined, the same floating-point operations in the same order, so the same bits) and the
    same closed form of the chunk, with nothing else per servo period: it records addval at
    each chunk's start and its target in ``rec``; :func:`_tracked` makes the chunks'
    descriptors from them with numpy. It stops before a chunk of no periods, at
    ``stop`` (progress reports), or after the update of a chunk that is not fast (the clamps'
    limits are settled: the caller checks, and passes them in ``consts``).

    ``st``: accum, addval, freq, old_pos_cmd, target, curr_dir; ``consts``: max_freq, max_ac,
    dt, recip_dt, freqscale and deltalim (≠ 0); ``lengths``: each chunk's base periods;
    ``pos_list``: the position commands (steps) of chunks ``ci`` … ``stop − 1``, command ``u``
    first. Returns the chunk it stopped at, the next command index, accum, addval, freq,
    old_pos_cmd, target, and whether that chunk's update has run.
    """
    accum, addval, freq, old_pos_cmd, target, curr_dir = st
    max_freq, max_ac, dt, recip_dt, freqscale, d = consts
    to_steps = 1.0 / (1 << PICKOFF)
    ac_dt = max_ac * dt  # (the same products as the follower's, made once)
    dt15 = 1.5 * dt
    half, one, up = HALF_STEP, ONE_STEP, curr_dir == 1
    a0_rec, tg_rec = (r.append for r in rec)
    done = 0
    for pos_cmd, m in zip(pos_list, lengths[ci:stop], strict=True):
        if m <= 0:
            break
        # update-freq, position mode (reference.follow_position, the same operations)
        vel_cmd = (pos_cmd - old_pos_cmd) * recip_dt
        curr_pos = (accum - half) * to_steps
        match_ac = max_ac if vel_cmd > freq else -max_ac
        match_time = (vel_cmd - freq) / match_ac
        avg_v = (vel_cmd + freq) * 0.5
        est_out = curr_pos + avg_v * match_time
        est_cmd = pos_cmd + vel_cmd * (match_time - dt15)
        est_err = est_out - est_cmd
        if match_time < dt:
            if -0.0001 < est_err < 0.0001:  # abs(est_err) < 0.0001
                new_vel = vel_cmd
            else:
                new_vel = vel_cmd - 0.5 * est_err * recip_dt
                if new_vel > freq + ac_dt:
                    new_vel = freq + ac_dt
                elif new_vel < freq - ac_dt:
                    new_vel = freq - ac_dt
        else:
            dv = -2.0 * match_ac * dt
            dp = dv * match_time
            if abs(est_err + dp * 2.0) < abs(est_err):
                match_ac = -match_ac
            new_vel = freq + match_ac * dt
        if new_vel > max_freq:
            new_vel = max_freq
        elif new_vel < -max_freq:
            new_vel = -max_freq
        freq = new_vel
        old_pos_cmd = pos_cmd
        target = int(freq * freqscale)
        # the chunk's closed form (run_fast's, with d ≠ 0), then whether it is fast
        a0 = addval
        if target >= a0:
            span = target - a0
            if m * d <= span:
                a_end = a0 + m * d
                total = m * a0 + d * (m * (m + 1) // 2)
            else:
                full = span // d
                a_end = target
                total = m * a0 + (d * (full * (full + 1) // 2) + span * (m - full))
        else:
            span = a0 - target
            if m * d <= span:
                a_end = a0 - m * d
                total = m * a0 - d * (m * (m + 1) // 2)
            else:
                full = span // d
                a_end = target
                total = m * a0 - (d * (full * (full + 1) // 2) + span * (m - full))
        if a0 >= 0:
            fast = 0 <= a_end <= one and a0 <= one and (up or (a0 == 0 and a_end == 0))
        else:
            fast = -one <= a_end < 0 and a0 >= -one and curr_dir == -1
        if not fast:
            return ci + done, u + done + 1, accum, addval, freq, old_pos_cmd, target, True
        a0_rec(a0)
        tg_rec(target)
        accum += total
        addval = a_end
        done += 1
    return ci + done, u + done, accum, addval, freq, old_pos_cmd, target, False


def _tracked(
    bounds: list[int],
    ci0: int,
    ci1: int,
    rec: tuple[list[int], list[int]],
    accum0: int,
    accum: int,
    d: int,
    curr_dir: int,
    ch: Channel,
) -> tuple[np.ndarray, int, _Pending | None]:
    """The fast chunks ``ci0`` … ``ci1 − 1`` that :func:`_track` ran (``rec``: their starting
    addval and their target; ``accum0``, ``accum``: the accumulator before and after them):
    their descriptor columns, the count they moved (one way: addval keeps its sign through
    fast chunks), and the last one that stepped as a pending chunk (None if none did). Each
    chunk's starting accumulator is ``accum0`` plus the closed-form sums of the chunks before."""
    k = np.array(bounds[ci0 : ci1 + 1], dtype=np.int64)
    k0, m = k[:-1], np.diff(k)
    a0, tg = (np.array(r, dtype=np.int64) for r in rec)
    sgn = np.where(tg >= a0, 1, -1)
    span = np.abs(tg - a0)
    n = ci1 - ci0
    sums = _addval_sum(m, a0, sgn, d, span, span // d)
    acc = np.empty(n, dtype=np.int64)
    acc[0] = accum0
    np.cumsum(sums[:-1], out=acc[1:])
    acc[1:] += accum0
    assert int(acc[-1] + sums[-1]) == accum  # the same closed form as _track's
    step_len = ch.step_len
    block = np.stack(
        (k0, m, a0, sgn, np.full(n, d), span, np.full(n, curr_dir), np.full(n, step_len), acc)
    )
    counts = np.append(acc >> PICKOFF, accum >> PICKOFF)
    stepped = np.flatnonzero(counts[1:] != counts[:-1])
    if not len(stepped):
        return block, 0, None
    j = int(stepped[-1])
    hold = step_len + ch.dir_hold_dly
    last: _Pending = (
        int(k0[j]), int(m[j]), int(acc[j]), int(a0[j]), int(sgn[j]), d, int(span[j]),
        int(counts[j + 1]), (step_len, hold, hold + ch.dir_setup),
    )  # fmt: skip
    return block, int(counts[-1] - counts[0]), last


def _addval_sum(i: Any, a0: Any, sgn: Any, d: Any, span: Any, full: Any) -> Any:
    """The sum of addval over the first ``i`` periods of a chunk (see the module docstring;
    ``full`` = span // d, 0 when d is 0), on numbers or int64 arrays."""
    j = np.minimum(i, full)
    return i * a0 + sgn * (d * (j * (j + 1) // 2) + span * np.maximum(i - full, 0))


def _fast_steps(cols: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The steps of the fast chunks ``cols`` (descriptor columns): their invocation indices, the
    chunk of each, and ``counts`` after each.

    In a fast chunk the accumulator moves one way by at most one step a period, so ``counts``
    passes each value between its values at the chunk's ends once: count c is reached at the
    first period i with accum0 + S(i) >= c·2^28 (counting up; below (c + 1)·2^28 counting down),
    S the closed-form sum of addval (a quadratic, then linear, in i). A float root gives i; it
    is kept where the exact integer test confirms it, else found by binary search."""
    k0, m, a0, sgn, d, span, _, _, acc0 = cols
    full = np.where(d != 0, span // np.where(d != 0, d, 1), 0)
    c0 = acc0 >> PICKOFF
    c1 = (acc0 + _addval_sum(m, a0, sgn, d, span, full)) >> PICKOFF
    n = np.abs(c1 - c0)
    # ~_STEPS_BLOCK steps at a time (whole chunks): the per-step temporaries stay small
    cum = np.cumsum(n)
    cuts = np.searchsorted(
        cum, np.arange(_STEPS_BLOCK, int(cum[-1]) if len(n) else 0, _STEPS_BLOCK)
    )
    bounds = [0, *sorted(set((cuts + 1).tolist()) - {len(n)}), len(n)]
    if len(bounds) == 2:
        return _chunk_steps(cols, full, c0, c1, n, 0)
    out = tuple(np.empty(int(cum[-1]), dtype=np.int64) for _ in range(3))  # filled block by block
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        s0, s1 = int(cum[a - 1]) if a else 0, int(cum[b - 1])
        got = _chunk_steps(cols[:, a:b], full[a:b], c0[a:b], c1[a:b], n[a:b], a)
        for whole, part in zip(out, got, strict=True):
            whole[s0:s1] = part
    return out  # type: ignore[return-value]


def _chunk_steps(
    cols: np.ndarray, full: np.ndarray, c0: np.ndarray, c1: np.ndarray, n: np.ndarray, first: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_fast_steps` of the chunks ``first`` … (``full``, ``c0``, ``c1``, ``n``: theirs,
    computed there)."""
    k0, m, a0, sgn, d, span, _, _, acc0 = cols
    chunk = np.repeat(np.arange(len(n)), n)
    r = np.arange(1, len(chunk) + 1) - np.repeat(np.cumsum(n) - n, n)  # 1..n within a chunk
    q = np.sign(c1 - c0)[chunk]
    count = c0[chunk] + q * r
    # q·S(i) >= need: counting up accum >= c·2^28; down −accum >= 1 − (c + 1)·2^28
    need = np.where(q > 0, count << PICKOFF, 1 - ((count + 1) << PICKOFF)) - q * acc0[chunk]
    ch = (a0, sgn, d, span, full)
    # per chunk, for the float root: the sum over its ramp and the addval after it
    at_full = _addval_sum(full, a0, sgn, d, span, full)[chunk]
    after = (a0 + sgn * span)[chunk]
    a0, sgn, d, span, full = (x[chunk] for x in ch)
    mm = m[chunk]

    def reached(i: np.ndarray, sel: slice | np.ndarray = slice(None)) -> np.ndarray:
        s = _addval_sum(i, a0[sel], sgn[sel], d[sel], span[sel], full[sel])
        return np.asarray(q[sel] * s >= need[sel])

    i = _float_root(q, a0, sgn, d, full, need, at_full, after)
    guess = np.clip(np.nan_to_num(np.ceil(i), nan=1.0), 1, mm).astype(np.int64)
    # right where reached at guess and not at guess − 1: q·S(guess − 1) is q·S(guess) less
    # q·addval(guess), addval(i) = a0 + sgn·min(i·d, span) (span is 0 where d is)
    at = q * _addval_sum(guess, a0, sgn, d, span, full)
    before = at - q * (a0 + sgn * np.minimum(guess * d, span))
    wrong = np.flatnonzero((at < need) | ((guess > 1) & (before >= need)))
    if len(wrong):  # binary search where the float root missed
        lo, hi = np.ones(len(wrong), dtype=np.int64), mm[wrong]
        for _ in range(int(hi.max()).bit_length()):
            mid = (lo + hi) >> 1
            ok = reached(mid, wrong)
            hi, lo = np.where(ok, mid, hi), np.where(ok, lo, mid + 1)
        guess[wrong] = lo
    return k0[chunk] + guess - 1, chunk + first, count


def _float_root(
    q: np.ndarray, a0: np.ndarray, sgn: np.ndarray, d: np.ndarray, full: np.ndarray,
    need: np.ndarray, at_full: np.ndarray, after: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """The real i with q·S(i) = need (see :func:`_fast_steps`), in floats: on the ramp
    (h/2)·i² + (q·a0 + h/2)·i with h = q·sgn·d, after it (``full`` periods, the sum
    ``at_full`` by then) linear at q·``after`` a period."""
    h = (q * sgn * d).astype(float)
    b = q * a0 + h / 2
    want = need.astype(float)
    with np.errstate(all="ignore"):
        i = 2 * want / (b + np.sqrt(np.maximum(b * b + 2 * h * want, 0.0)))
        return np.where(i > full, full + (want - (q * at_full).astype(float)) / (q * after), i)


def _runs(starts: np.ndarray, ends: np.ndarray, n_periods: int) -> np.ndarray:
    """Toggle indices of a pin that is high on the sorted, disjoint, non-empty periods
    [starts[j], ends[j]) and low elsewhere (touching runs merge; toggles from ``n_periods`` on
    are dropped)."""
    apart = ends[:-1] != starts[1:]
    rise = np.concatenate(([True], apart))
    fall = np.concatenate((apart, [True])) & (ends < n_periods)
    out = np.empty(2 * len(starts), dtype=np.int64)
    out[0::2], out[1::2] = starts, ends
    keep = np.empty(2 * len(starts), dtype=bool)
    keep[0::2], keep[1::2] = rise, fall
    return out[keep]


def _changes(at: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Where a piecewise-constant series (``values[j]`` from ``at[j]`` on, 0 before) changes."""
    prev = np.concatenate(([0], values[:-1]))
    return at[values != prev]


def _pass2(
    kind: StepType,
    base: int,
    n_periods: int,
    cols: np.ndarray,
    exact: dict[int, tuple[np.ndarray, np.ndarray]],
) -> tuple[dict[str, np.ndarray], np.ndarray, np.ndarray]:
    """Each pin's toggles and the ``counts`` changes from the chunk descriptors, step by step.

    The steps of fast chunks come from :func:`_fast_steps`, those of exact chunks from their
    per-period increments; then STEP is high for ceil(steplen/P) periods from each step (cut
    short by the next step: timer1 restarts), DIR (type 0) follows the direction chunk by chunk,
    up/down (type 1) carry each pulse on the line of the direction at its step (the direction
    cannot change while timer2 ≥ timer1 runs), and a phase type's state moves by the direction
    at each step."""
    k0, dirs, lens, acc0 = cols[0], cols[6], cols[7], cols[8]
    nper = -(-lens // base)  # ceil(step_len / P): the periods timer1 keeps STEP high
    is_fast = np.ones(cols.shape[1], dtype=bool)
    is_fast[list(exact)] = False
    fast = np.flatnonzero(is_fast)
    s_at, s_chunk, c_val = _fast_steps(cols[:, fast])
    s_chunk = fast[s_chunk]
    c_at = s_at
    # the direction, chunk by chunk (exact chunks: period by period)
    d_at, d_val = k0[fast], dirs[fast]
    s_dir = dirs[s_chunk]  # each step's direction: its chunk's (exact chunks: its period's)
    if exact:
        # an exact chunk's steps, count changes and per-period directions go between the fast
        # chunks before and after it (chunks cover disjoint, ordered periods): inserted there
        s_before = np.searchsorted(s_chunk, list(exact))  # fast steps before each exact chunk
        d_before = np.searchsorted(fast, list(exact))  # fast chunks before it
        ins: list[list[np.ndarray]] = [[] for _ in range(10)]
        for (ci, (inc, e_dir)), sb, db in zip(exact.items(), s_before, d_before, strict=True):
            start = int(k0[ci])
            accum = np.cumsum(inc) + acc0[ci]
            prev = np.concatenate((acc0[ci : ci + 1], accum[:-1]))
            steps = np.flatnonzero((accum ^ prev) & ONE_STEP)
            counts = accum >> PICKOFF
            moved = np.flatnonzero(counts != (prev >> PICKOFF))
            for part, value in zip(ins, (
                np.full(len(steps), sb), steps + start, np.full(len(steps), ci), e_dir[steps],
                np.full(len(moved), sb), moved + start, counts[moved],
                np.full(len(inc), db), np.arange(start, start + len(inc)), e_dir,
            ), strict=True):  # fmt: skip
                part.append(value)
        sp, sa, sc, sd, cp, ca, cv, dp, da, dv = (np.concatenate(p) for p in ins)
        s_at, s_chunk, s_dir = (
            np.insert(s_at, sp, sa),
            np.insert(s_chunk, sp, sc),
            np.insert(s_dir, sp, sd),
        )
        c_at, c_val = np.insert(c_at, cp, ca), np.insert(c_val, cp, cv)
        d_at, d_val = np.insert(d_at, dp, da), np.insert(d_val, dp, dv)
    toggles: dict[str, np.ndarray] = {}
    if kind.kind == "phases":
        state = np.cumsum(s_dir) % max(kind.cycle, 1)
        lut = np.asarray(kind.states, dtype=np.int64)
        at = np.concatenate(([0], s_at)) if not len(s_at) or s_at[0] else s_at
        bits = np.concatenate((lut[:1], lut[state])) if len(at) > len(s_at) else lut[state]
        for b, pin in enumerate(kind.outputs):
            toggles[pin] = _changes(at, (bits >> b) & 1)
    else:
        # STEP high from each step for nper periods or until the next step
        ends = s_at + nper[s_chunk]
        ends[:-1] = np.minimum(ends[:-1], s_at[1:])
        high = ends > s_at
        if kind.kind == "step-dir":
            step, direction = kind.outputs
            toggles[step] = _runs(s_at[high], ends[high], n_periods)
            toggles[direction] = _changes(d_at, (d_val < 0).astype(np.int64))
        else:
            lines = (high & (s_dir >= 0), high & (s_dir < 0))
            for pin, line in zip(kind.outputs, lines, strict=True):
                toggles[pin] = _runs(s_at[line], ends[line], n_periods)
    return toggles, c_at, c_val
