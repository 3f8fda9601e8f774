"""What type checkers see of ``touchbench``: the Python API that ``__init__.py`` loads lazily."""

from touchbench.app.python.api import bench as bench
from touchbench.app.python.api import extract as extract
from touchbench.app.python.api import simulate as simulate
from touchbench.app.python.api import train as train
from touchbench.app.python.client import Client as Client
from touchbench.app.python.errors import ServiceError as ServiceError
from touchbench.app.python.leaderboard import Leaderboard as Leaderboard

__all__ = ["Client", "Leaderboard", "ServiceError", "bench", "extract", "simulate", "train"]
