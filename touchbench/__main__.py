"""``python -m touchbench``: the command line."""

from touchbench.app.cli.main import run

if __name__ == "__main__":
    run()
