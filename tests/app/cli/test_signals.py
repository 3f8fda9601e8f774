"""Interrupts a loop hears between two items (the ROS node's): the first only asks it to
stop, the end of the block raises; a second one raises at once.  A command interrupted
exits with its signal's status."""

from __future__ import annotations

import signal
from pathlib import Path

import pytest

from tests.support.cli_runner import run_cli
from tests.support.synthetic import touch_arff
from touchbench.app.cli.signals import Interrupted, deferred_interrupts
from touchbench.app.services import datasets


def test_the_first_interrupt_asks_and_the_end_of_the_block_raises() -> None:
    asked: list[str] = []
    finished = False
    with pytest.raises(Interrupted) as raised, deferred_interrupts(lambda: asked.append("stop")):
        signal.raise_signal(signal.SIGTERM)
        finished = True  # the work goes on to its end
    assert asked == ["stop"] and finished
    assert raised.value.exit_code == 143
    assert signal.getsignal(signal.SIGTERM) is not None  # the previous handler is back


def test_a_second_interrupt_raises_at_once_and_a_cut_wait_is_not_the_news() -> None:
    with pytest.raises(Interrupted) as raised, deferred_interrupts(lambda: None):
        signal.raise_signal(signal.SIGINT)
        signal.raise_signal(signal.SIGINT)
        pytest.fail("the second interrupt did not raise")
    assert raised.value.exit_code == 130
    with pytest.raises(Interrupted), deferred_interrupts(lambda: None):
        signal.raise_signal(signal.SIGINT)
        raise ValueError("the wait the stop cut short failed")


@pytest.mark.parametrize(("sig", "code"), [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_a_command_that_leaves_the_interrupt_to_typer_exits_with_its_signal(
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    sig: signal.Signals,
    code: int,
) -> None:
    """typer answers any interrupt a command does not catch with the status 130: a SIGTERM
    in the middle of ``import`` (or while a command loads its modules) still exits 143."""

    def interrupted(*args: object, **kwargs: object) -> None:
        signal.raise_signal(sig)

    monkeypatch.setattr(datasets, "import_file", interrupted)
    url = f"sqlite:///{tmp_path / 'touchbench.db'}"
    done = run_cli(capsys, url, "import", str(touch_arff(tmp_path / "touch.arff", n=30)))
    assert (done.code, done.err) == (code, "touchbench: interrupted\n")
    assert run_cli(capsys, url, "datasets", "--json").out.count('"name"') == 0
