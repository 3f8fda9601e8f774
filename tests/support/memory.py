"""Peak memory of what a test runs: the service's (``VmHWM``) and a CLI process's."""

from __future__ import annotations

import re
from pathlib import Path

from tests.support.service import Server

DATA_URI = re.compile(r'src="(data:image/svg\+xml;base64,[^"]+)"')


def peak_rss_mb(server: Server) -> float:
    """The service process's peak resident memory (``VmHWM``), in MB."""
    assert server.process is not None
    status = Path(f"/proc/{server.process.pid}/status").read_text()
    match = re.search(r"^VmHWM:\s+(\d+) kB", status, re.MULTILINE)
    assert match, status
    return int(match.group(1)) / 1024


REPOSITORY = Path(__file__).resolve().parents[3]


CLI_WITH_PEAK = """
import sys
from touchbench.app.cli.main import main
code = main(sys.argv[1:])
with open("/proc/self/status") as status:
    peak = next(line.split()[1] for line in status if line.startswith("VmHWM:"))
print(f"peak-rss-kb {peak}", file=sys.stderr)
sys.exit(code)
"""
