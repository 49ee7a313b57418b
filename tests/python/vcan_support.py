"""Whether a SocketCAN vcan can be had here: natively, or in the QEMU guest
that hil/vcan_run.sh boots from /boot/vmlinuz-* (DESIGN.md section 5)."""
from __future__ import annotations

import glob
import socket

import pytest


def host_has_can() -> bool:
    try:
        socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
        return True
    except (AttributeError, OSError):
        return False


needs_vcan = pytest.mark.skipif(
    not glob.glob("/boot/vmlinuz-*") and not host_has_can(),
    reason="no SocketCAN in the host kernel and no /boot/vmlinuz-* for a QEMU guest "
    "(run 'bash scripts/setup.sh' as root)",
)
