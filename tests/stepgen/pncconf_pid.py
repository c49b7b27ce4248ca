"""A LinuxCNC INI/HAL pair written the way pncconf writes a stepgen joint closed with ``pid``.

Every line below follows a documented fact (pid reference ``shared/reference/pid-linuxcnc.md``):

- [PNC] ``build_HAL.py``: ``loadrt pid names=pid.x,pid.y`` (one instance per axis letter),
  ``addf pid.x.do-pid-calcs servo-thread``, and ``build_pid``'s lines, spacing included:
  ``setp   pid.x.Pgain     [JOINT_0]P`` … ``setp   pid.x.maxoutput [JOINT_0]MAX_OUTPUT``,
  ``setp   pid.x.error-previous-target true``, for a stepper ``setp   pid.x.maxerror 0.012700``
  (``%f`` of 0.0127 mm, the metric value), and the nets ``x-index-enable``, ``x-enable``,
  ``x-pos-cmd => pid.x.command``, ``x-pos-fb => pid.x.feedback``, ``x-output <= pid.x.output``;
- §3 wiring: pid.output → stepgen velocity-cmd, stepgen position-fb → pid.feedback and
  joint.N.motor-pos-fb, joint.N.motor-pos-cmd → pid.command; the software stepgen in velocity
  mode is ``loadrt stepgen … ctrl_type=v``;
- §3 typical values ([PNC] defaults for a stepgen joint): P = 1/servo period in s (1000 for
  1 ms), I = D = FF0 = FF2 = BIAS = 0, FF1 = 1, DEADBAND = 0, MAX_OUTPUT = 0,
  STEPGEN_MAXVEL/MAXACCEL = 1.25 × MAX_VELOCITY/MAX_ACCELERATION, FERROR/MIN_FERROR 10/1 mm.

Joint 1 (pid.y) is the same wiring with a hand-tuned P = 800, so a test can tell the two apart.
pncconf itself drives a Mesa card's stepgen; this pair is the same pid block around LinuxCNC's
software stepgen (reference §3: "No config in the repo combines the software stepgen with
pid"), which is what ``stepgen simulate --pid`` models.
"""

from __future__ import annotations

from pathlib import Path

INI = """\
# pncconf-style INI (metric)
[EMCMOT]
EMCMOT = motmod
COMM_TIMEOUT = 1.0
BASE_PERIOD = 25000
SERVO_PERIOD = 1000000

[KINS]
JOINTS = 2
KINEMATICS = trivkins coordinates=XY

[AXIS_X]
MAX_VELOCITY = 20.0
MAX_ACCELERATION = 200.0

[JOINT_0]
TYPE = LINEAR
HOME = 0.0
FERROR = 10.0
MIN_FERROR = 1.0
MAX_VELOCITY = 20.0
MAX_ACCELERATION = 200.0
# The values below should be 25% larger than MAX_VELOCITY and MAX_ACCELERATION
STEPGEN_MAXVEL = 25.0
STEPGEN_MAXACCEL = 250.0
P = 1000.0
I = 0.0
D = 0.0
FF0 = 0.0
FF1 = 1.0
FF2 = 0.0
BIAS = 0.0
DEADBAND = 0.0
MAX_OUTPUT = 0.0
# these are in nanoseconds
DIRSETUP   = 10000
DIRHOLD    = 10000
STEPLEN    = 5000
STEPSPACE  = 5000
STEP_SCALE = 200.0

[AXIS_Y]
MAX_VELOCITY = 20.0
MAX_ACCELERATION = 200.0

[JOINT_1]
TYPE = LINEAR
HOME = 0.0
FERROR = 10.0
MIN_FERROR = 1.0
MAX_VELOCITY = 20.0
MAX_ACCELERATION = 200.0
STEPGEN_MAXVEL = 25.0
STEPGEN_MAXACCEL = 250.0
P = 800.0
I = 0.0
D = 0.0
FF0 = 0.0
FF1 = 1.0
FF2 = 0.0
BIAS = 0.0
DEADBAND = 0.0
MAX_OUTPUT = 0.0
DIRSETUP   = 10000
DIRHOLD    = 10000
STEPLEN    = 5000
STEPSPACE  = 5000
STEP_SCALE = 200.0
"""


def _joint(let: str, j: int) -> str:
    return f"""\
#*******************
#  AXIS {let.upper()} JOINT {j}
#*******************

setp   pid.{let}.Pgain     [JOINT_{j}]P
setp   pid.{let}.Igain     [JOINT_{j}]I
setp   pid.{let}.Dgain     [JOINT_{j}]D
setp   pid.{let}.bias      [JOINT_{j}]BIAS
setp   pid.{let}.FF0       [JOINT_{j}]FF0
setp   pid.{let}.FF1       [JOINT_{j}]FF1
setp   pid.{let}.FF2       [JOINT_{j}]FF2
setp   pid.{let}.deadband  [JOINT_{j}]DEADBAND
setp   pid.{let}.maxoutput [JOINT_{j}]MAX_OUTPUT
setp   pid.{let}.error-previous-target true
# This setting is to limit bogus stepgen
# velocity corrections caused by position
# feedback sample time jitter.
setp   pid.{let}.maxerror 0.012700

net {let}-index-enable  =>  pid.{let}.index-enable
net {let}-enable        =>  pid.{let}.enable
net {let}-pos-cmd       =>  pid.{let}.command
net {let}-pos-fb        =>  pid.{let}.feedback
net {let}-output        <=  pid.{let}.output

# Step Gen signals/setup

setp   stepgen.{j}.dirsetup        [JOINT_{j}]DIRSETUP
setp   stepgen.{j}.dirhold         [JOINT_{j}]DIRHOLD
setp   stepgen.{j}.steplen         [JOINT_{j}]STEPLEN
setp   stepgen.{j}.stepspace       [JOINT_{j}]STEPSPACE
setp   stepgen.{j}.position-scale  [JOINT_{j}]STEP_SCALE
setp   stepgen.{j}.maxaccel        [JOINT_{j}]STEPGEN_MAXACCEL
setp   stepgen.{j}.maxvel          [JOINT_{j}]STEPGEN_MAXVEL

net {let}-pos-fb     <=  stepgen.{j}.position-fb
net {let}-output     =>  stepgen.{j}.velocity-cmd
net {let}-enable     =>  stepgen.{j}.enable

# ---closedloop stepper signals---

net {let}-pos-cmd    <= joint.{j}.motor-pos-cmd
net {let}-pos-fb     => joint.{j}.motor-pos-fb
net {let}-enable     <= joint.{j}.amp-enable-out
net {let}-index-enable  joint.{j}.index-enable

"""


HAL = (
    """\
# pncconf-style HAL: software stepgen in velocity mode, closed with pid
loadrt [KINS]KINEMATICS
loadrt [EMCMOT]EMCMOT base_period_nsec=[EMCMOT]BASE_PERIOD servo_period_nsec=[EMCMOT]SERVO_PERIOD num_joints=[KINS]JOINTS
loadrt stepgen step_type=0,0 ctrl_type=v,v
loadrt pid names=pid.x,pid.y

addf stepgen.make-pulses           base-thread
addf stepgen.capture-position      servo-thread
addf motion-command-handler        servo-thread
addf motion-controller             servo-thread
addf pid.x.do-pid-calcs       servo-thread
addf pid.y.do-pid-calcs       servo-thread
addf stepgen.update-freq           servo-thread

"""
    + _joint("x", 0)
    + _joint("y", 1)
)


def write_pair(folder: Path) -> tuple[Path, Path]:
    """Write ``machine.ini`` and ``machine.hal`` into ``folder``."""
    ini = folder / "machine.ini"
    hal = folder / "machine.hal"
    ini.write_text(INI)
    hal.write_text(HAL)
    return ini, hal


def line_of(text: str, needle: str) -> int:
    """The 1-based number of the first line containing ``needle``."""
    for no, line in enumerate(text.splitlines(), 1):
        if needle in line:
            return no
    raise AssertionError(needle)
