"""LinuxCNC's ``pid`` HAL component, one ``do-pid-calcs`` call per servo period — bit for bit.

A behavioural model of ``src/hal/components/pid.c`` as specified in
``shared/reference/pid-linuxcnc.md`` (section numbers below refer to it), written from that
description only. :meth:`Pid.calc` follows §2's order step by step, in IEEE doubles (Python
floats) with the same operation grouping, so its pins match the compiled component exactly on
x86-64 (the reference's vectors A–D, §5, are tests).

Modelled: every gain and limit pin (Pgain … FF3, bias, deadband, maxerror, maxerrorI,
maxerrorD, maxcmdD/DD/DDD, maxoutput), ``enable``, ``error-previous-target`` (default TRUE),
``index-enable`` (its falling edge uses the current command and freezes the derivatives),
linked ``command-deriv``/``feedback-deriv``, the saturation pins, the anti-windup (integration
stops only in the direction that deepens the previous period's saturation) and ``tune-mode``'s
reset (§2 step 5). Quirks kept: Pgain defaults to 1.0; errorI accumulates even when Igain = 0;
the first call after load sees ``prev_cmd = 0``; with ``maxoutput = 0`` the previous
``limit_state`` is left as it was (§6.3); a NaN error becomes 0 in the deadband. Not modelled:
the relay autotuner's state machine (§4.5) — ``stepgen tune`` implements the documented manual
method instead.

Units (a position loop driving a velocity-mode stepgen): command/feedback in position units,
output in units/s, Pgain 1/s, Igain 1/s², Dgain dimensionless, FF1 dimensionless.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

__all__ = ["SATURATED_COUNT_MAX", "Pid", "PidGains"]

#: ``saturated-count`` stops here (s32).
SATURATED_COUNT_MAX = 2**31 - 1


@dataclass(frozen=True)
class PidGains:
    """The tunable input pins of one ``pid.N`` and their LinuxCNC defaults (§1).

    Every ``max*`` limit: 0 means no limit.
    """

    Pgain: float = 1.0
    Igain: float = 0.0
    Dgain: float = 0.0
    bias: float = 0.0
    FF0: float = 0.0
    FF1: float = 0.0
    FF2: float = 0.0
    FF3: float = 0.0
    deadband: float = 0.0
    maxerror: float = 0.0
    maxerrorI: float = 0.0
    maxerrorD: float = 0.0
    maxcmdD: float = 0.0
    maxcmdDD: float = 0.0
    maxcmdDDD: float = 0.0
    maxoutput: float = 0.0
    error_previous_target: bool = True

    @classmethod
    def pin_names(cls) -> tuple[str, ...]:
        """The HAL pin names (``error-previous-target`` with dashes)."""
        return tuple(f.name.replace("_", "-") for f in fields(cls))


def _clamp(x: float, limit: float) -> float:
    """±limit clamp as the C writes it (0 = none; a NaN passes through)."""
    if limit != 0.0:
        if x > limit:
            return limit
        if x < -limit:
            return -limit
    return x


class Pid:
    """One ``pid.N`` instance: its gains, output pins and hidden state, all zero after load.

    Gains may be replaced between calls (``pid.gains = replace(pid.gains, Pgain=…)``): in
    LinuxCNC they are pins.
    """

    def __init__(self, gains: PidGains | None = None) -> None:
        self.gains = gains if gains is not None else PidGains()
        # output pins
        self.error = 0.0
        self.output = 0.0
        self.saturated = False
        self.saturated_s = 0.0
        self.saturated_count = 0
        # debug pins / hidden storage
        self.errorI = 0.0
        self.errorD = 0.0
        self.commandD = 0.0
        self.commandDD = 0.0
        self.commandDDD = 0.0
        # state
        self.prev_cmd = 0.0
        self.prev_fb = 0.0
        self.prev_ie = False
        self.limit_state = 0
        self.cmdv_int = 0.0
        self.fbv_int = 0.0

    def calc(
        self,
        period_ns: int,
        command: float,
        feedback: float,
        enable: bool = True,
        *,
        index_enable: bool = False,
        command_deriv: float | None = None,
        feedback_deriv: float | None = None,
        tune_mode: bool = False,
    ) -> float:
        """One ``do-pid-calcs`` call (§2); returns ``output``.

        Args:
            period_ns: the servo thread's nominal period N (ns).
            command, feedback: the ``command`` and ``feedback`` pins.
            enable: the ``enable`` pin.
            index_enable: the ``index-enable`` pin.
            command_deriv, feedback_deriv: the signal on a *linked* ``-deriv`` pin, None when
                the pin is unlinked (the internal estimate is used).
            tune_mode: the ``tune-mode`` pin (resets the loop, output 0).
        """
        g = self.gains
        period = period_ns * 1e-9  # step 2
        periodrecip = 1.0 / period
        c = command  # step 3
        f = feedback
        falling = self.prev_ie and not index_enable
        # step 4: raw error
        if g.error_previous_target and not falling:
            e = self.prev_cmd - f
        else:
            e = c - f
        self.error = e
        if tune_mode:  # step 5
            self.errorI = self.errorD = self.commandD = self.commandDD = 0.0
            self.prev_cmd = 0.0
            self.limit_state = 0
            self.output = 0.0
            return 0.0
        e = _clamp(e, g.maxerror)  # step 6
        db = g.deadband  # step 7
        if e > db:
            e = e - db
        elif e < -db:
            e = e + db
        else:
            e = 0.0
        # step 8: integrator with anti-windup
        if enable:
            if e * self.limit_state <= 0.0:
                self.errorI = self.errorI + e * period
            self.errorI = _clamp(self.errorI, g.maxerrorI)
        else:
            self.errorI = 0.0
        # step 9: derivative estimates (frozen on the falling edge of index-enable)
        if not falling:
            self.cmdv_int = (c - self.prev_cmd) * periodrecip
            self.fbv_int = (f - self.prev_fb) * periodrecip
        # step 10
        v_c = self.cmdv_int if command_deriv is None else command_deriv
        v_f = self.fbv_int if feedback_deriv is None else feedback_deriv
        self.errorD = _clamp(v_c - v_f, g.maxerrorD)  # step 11
        old_cmd_d = self.commandD  # step 12
        self.commandD = _clamp(v_c, g.maxcmdD)
        self.prev_ie = index_enable  # step 13
        self.prev_cmd = c
        self.prev_fb = f
        # step 14
        old_cmd_dd = self.commandDD
        self.commandDD = _clamp((self.commandD - old_cmd_d) * periodrecip, g.maxcmdDD)
        self.commandDDD = _clamp((self.commandDD - old_cmd_dd) * periodrecip, g.maxcmdDDD)
        # step 15: output
        if enable:
            u = ((g.bias + g.Pgain * e) + g.Igain * self.errorI) + g.Dgain * self.errorD
            u = u + (
                ((c * g.FF0 + self.commandD * g.FF1) + self.commandDD * g.FF2)
                + self.commandDDD * g.FF3
            )
            if g.maxoutput != 0.0:
                if u > g.maxoutput:
                    u = g.maxoutput
                    self.limit_state = 1
                elif u < -g.maxoutput:
                    u = -g.maxoutput
                    self.limit_state = -1
                else:
                    self.limit_state = 0
        else:
            u = 0.0
            self.limit_state = 0
        self.output = u  # step 16
        if self.limit_state != 0:  # step 17
            self.saturated = True
            self.saturated_s += period_ns * 1e-9
            if self.saturated_count != SATURATED_COUNT_MAX:
                self.saturated_count += 1
        else:
            self.saturated = False
            self.saturated_s = 0.0
            self.saturated_count = 0
        return u
