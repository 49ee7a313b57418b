"""The TCU a closed-loop shift runs against: the frame loop in-process (InprocTcu, wc_replay --lockstep), the
same firmware code as wc_tcu on vcan (runner.run_on_vcan replays a case's inputs to it)."""
from __future__ import annotations

import subprocess
from pathlib import Path

from ..util import canlog
from .scenarios import ROOT, SHIFT_TOML, TCU_CALIBRATION, WC_REPLAY, ShiftError


class InprocTcu:
    """The frame loop in-process: wc_replay --lockstep through a pipe."""

    def __init__(self, shift_name: str, theta_start_degC: float, overrides: dict | None = None,
                 calibration: str = TCU_CALIBRATION, program: Path = WC_REPLAY, adaptation_file: Path | None = None):
        """adaptation_file: wc_replay --adaptation-file, the learned values (DESIGN 12) read at the start and
        written (atomically) at each shift's end; None: none (the calibration's values, nothing written)."""
        if not Path(program).is_file():
            raise ShiftError(f"{program} not built (cmake --preset host-release && cmake --build --preset host-release)")
        cmd = [str(program), "-", "--lockstep", "--calibration", calibration, "--theta-start",
               f"{theta_start_degC:.6g}", "--shift", shift_name]
        for k, v in (overrides or {}).items():
            cmd += ["--set", f"{k}={v:.9g}"]
        if adaptation_file is not None:
            cmd += ["--adaptation-file", str(adaptation_file)]
        self.proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, bufsize=1)

    @staticmethod
    def supports_adaptation_file(program: Path = WC_REPLAY) -> bool:
        """wc_replay takes --adaptation-file (its usage text names it)."""
        if not Path(program).is_file():
            return False
        res = subprocess.run([str(program)], capture_output=True, text=True)
        return "--adaptation-file" in res.stdout + res.stderr

    def _write(self, lines: str) -> None:
        try:
            self.proc.stdin.write(lines)
            self.proc.stdin.flush()
        except BrokenPipeError:
            raise ShiftError(f"wc_replay stopped: {self.proc.stderr.read().strip()}") from None

    def _read_period(self) -> list[tuple[int, bytes]]:
        """One period's output frames, up to wc_replay --lockstep's "." line."""
        out = []
        while True:
            line = self.proc.stdout.readline()
            if not line:
                raise ShiftError(f"wc_replay stopped: {self.proc.stderr.read().strip()}")
            line = line.strip()
            if line == ".":
                return out
            ident, data = line.split()[2].split("#")
            out.append((int(ident, 16), bytes.fromhex(data)))

    @staticmethod
    def _lines(t_s: float, frames) -> str:
        return "".join(f"({t_s:.6f}) vcan0 {m.arbitration_id:03X}#{bytes(m.data).hex().upper()}\n" for m in frames)

    def exchange(self, t_s: float, frames) -> list[tuple[int, bytes]]:
        self._write(self._lines(t_s, frames))
        return self._read_period()

    def run_open_loop(self, t_s: float, steps, chunk: int = 200) -> list[tuple[int, bytes]]:
        """Periods whose inputs do not depend on the TCU's outputs (steps: each period's frames), written
        ahead in chunks (no round trip per period; a chunk's input and output stay below a pipe's buffer)
        and their outputs read after; returns the last period's output frames."""
        steps = list(steps)
        last: list[tuple[int, bytes]] = []
        for c0 in range(0, len(steps), chunk):
            part = steps[c0:c0 + chunk]
            self._write("".join(self._lines(t_s + (c0 + j) * 1e-3, frames) for j, frames in enumerate(part)))
            for _ in part:
                last = self._read_period()
        return last

    def close(self):
        if self.proc.stdin:
            self.proc.stdin.close()
        self.proc.wait(timeout=10)
        self.proc.stdout.close()
        self.proc.stderr.close()
