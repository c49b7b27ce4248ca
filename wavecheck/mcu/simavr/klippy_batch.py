# klippy_batch: run Klipper's host program (klippy) in batch mode, and let it write all it queued.
#
# Copyright (C) 2026 the wavecheck authors
# SPDX-License-Identifier: GPL-3.0-or-later
#
# This program imports klippy (GPL-3.0) and is therefore GPL-3.0-or-later. wavecheck (MIT) runs
# it as a separate process and reads the file it writes; it does not import it.
#
# Usage: python klippy_batch.py KLIPPY_DIR [klippy.py's arguments: printer.cfg -i job.gcode
# -o job.serial -d klipper.dict]
#
# Why: in batch mode klippy hands each message to its serial queue, whose background thread
# writes the output file (klippy/chelper/serialqueue.c); at exit SerialReader.disconnect
# (klippy/serialhdl.py:217-225) stops that thread at once (serialqueue_exit), whatever it still
# holds. On a busy machine the file then lacks the end of the job, or everything after the
# configuration, while klippy's log shows the job run to its end. Here disconnect first waits,
# for at most DRAIN_S, until the queue reports no ready and no upcoming bytes
# (serialqueue_get_stats), and says so on stderr if it does not drain.
import os
import re
import sys
import time
from typing import Any

DRAIN_S = 60.0


def _pending(reader: Any) -> int:
    stats = dict(re.findall(r"(\w+)=(\S+)", reader.stats(0.0)))
    return int(stats.get("ready_bytes", 0)) + int(stats.get("upcoming_bytes", 0))


def main() -> None:
    klippy_dir = sys.argv.pop(1)
    sys.path.insert(0, klippy_dir)
    sys.argv[0] = os.path.join(klippy_dir, "klippy.py")
    import klippy
    import serialhdl

    plain = serialhdl.SerialReader.disconnect

    def disconnect(self: Any) -> None:
        deadline = time.monotonic() + DRAIN_S
        while self.serialqueue is not None and _pending(self) and time.monotonic() < deadline:
            time.sleep(0.01)
        if self.serialqueue is not None and _pending(self):
            sys.stderr.write(f"klippy_batch: the serial queue did not drain in {DRAIN_S:g} s\n")
        plain(self)

    serialhdl.SerialReader.disconnect = disconnect
    klippy.main()


if __name__ == "__main__":
    main()
