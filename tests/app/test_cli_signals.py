"""Interrupts a loop hears between two items (the ROS node's): the first only asks it to
stop, the end of the block raises; a second one raises at once."""

from __future__ import annotations

import signal

import pytest

from app.cli.signals import Interrupted, deferred_interrupts


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
