"""Read and edit a VCD's value changes as text, independently of wavecheck's reader."""

from __future__ import annotations

from pathlib import Path


class VcdText:
    """A VCD split into its header and ``time → [change lines]`` blocks (dumpvars at time 0)."""

    def __init__(self, path: Path) -> None:
        text = path.read_text()
        head, body = text.split("$enddefinitions $end", 1)
        self.header = head + "$enddefinitions $end\n"
        self.ids: dict[str, str] = {}
        for line in head.splitlines():
            parts = line.split()
            if parts[:1] == ["$var"]:
                self.ids[parts[4]] = parts[3]
        self.blocks: dict[int, list[str]] = {}
        t = 0
        for tok_line in body.splitlines():
            line = tok_line.strip()
            if not line or line in ("$dumpvars", "$end"):
                continue
            if line.startswith("#"):
                t = int(line[1:])
                self.blocks.setdefault(t, [])
            else:
                self.blocks.setdefault(t, []).append(line)

    def changes(self, name: str) -> list[tuple[int, str]]:
        """(time, value) of every change of 1-bit signal ``name``, dumpvars included."""
        code = self.ids[name]
        return [
            (t, line[0])
            for t, lines in sorted(self.blocks.items())
            for line in lines
            if not line.startswith(("b", "r")) and line[1:] == code
        ]

    def vector(self, name: str, width: int = 32) -> list[tuple[int, int]]:
        """(time, signed value) of every change of vector ``name``."""
        code = self.ids[name]
        out = []
        for t, lines in sorted(self.blocks.items()):
            for line in lines:
                if line.startswith("b") and line.split()[1] == code:
                    v = int(line.split()[0][1:], 2)
                    out.append((t, v - (1 << width) if v >> (width - 1) else v))
        return out

    def move(self, name: str, value: str, old_t: int, new_t: int) -> None:
        """Move the change of ``name`` to ``value`` at ``old_t`` to ``new_t``."""
        line = value + self.ids[name]
        self.blocks[old_t].remove(line)
        self.blocks.setdefault(new_t, []).append(line)

    def write(self, path: Path) -> Path:
        lines = [self.header.rstrip("\n"), "#0", "$dumpvars", *self.blocks.get(0, []), "$end"]
        for t in sorted(self.blocks):
            if t == 0:
                continue
            lines.append(f"#{t}")
            lines += self.blocks[t]
        path.write_text("\n".join(lines) + "\n")
        return path
