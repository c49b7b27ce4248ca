"""Klipper's Kconfig step with kconfiglib from PyPI (Klipper ships its own copy in lib/kconfiglib,
which a bare source tree may lack).

Klipper's Makefile runs ``$(PYTHON) lib/kconfiglib/olddefconfig.py src/Kconfig`` and
``KCONFIG_AUTOHEADER=out/autoconf.h $(PYTHON) lib/kconfiglib/genconfig.py src/Kconfig``
(``Makefile:108-114``). Klipper's C code tests every option with ``#if`` and ``if (CONFIG_X)``
(``src/generic/serial_irq.c:82``, ``src/initial_pins.c:19``), so its header must define the options
that are off (as 0) and the strings that are not shown (as ""), which PyPI's ``genconfig`` leaves
out. The two scripts below are written into ``lib/kconfiglib/`` of the build's copy of the tree.
"""

from __future__ import annotations

__all__ = ["GENCONFIG", "OLDDEFCONFIG"]

#: lib/kconfiglib/olddefconfig.py: PyPI's own, found past the script's folder (which would
#: otherwise shadow it).
OLDDEFCONFIG = b"""\
import runpy
import sys

sys.path.pop(0)
runpy.run_module("olddefconfig", run_name="__main__")
"""

#: lib/kconfiglib/genconfig.py: out/autoconf.h with every symbol: booleans as 1 or 0, strings
#: quoted, numbers as they are.
GENCONFIG = b"""\
import os
import sys

sys.path.pop(0)
import kconfiglib

kconf = kconfiglib.Kconfig(sys.argv[1], warn=False)
kconf.load_config(os.environ.get("KCONFIG_CONFIG", ".config"))
out = []
for sym in kconf.unique_defined_syms:
    value = sym.str_value
    if sym.orig_type in (kconfiglib.BOOL, kconfiglib.TRISTATE):
        out.append("#define CONFIG_%s %d\\n" % (sym.name, value == "y"))
    elif sym.orig_type == kconfiglib.STRING:
        out.append('#define CONFIG_%s "%s"\\n' % (sym.name, kconfiglib.escape(value)))
    elif value:
        out.append("#define CONFIG_%s %s\\n" % (sym.name, value))
with open(os.environ["KCONFIG_AUTOHEADER"], "w") as f:
    f.writelines(out)
"""
