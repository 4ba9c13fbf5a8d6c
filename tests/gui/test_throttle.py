"""The coalescing of fast cursor updates (bladecam_gui.widgets.throttle)."""

from bladecam_gui.widgets.throttle import Throttle


def test_throttle_applies_at_once_then_the_latest_value_per_tick(qtbot):
    seen = []
    th = Throttle(seen.append, interval_ms=60)
    th.request(1)
    assert seen == [1]  # idle: at once
    th.request(2)
    th.request(3)
    assert seen == [1]  # within the tick: kept
    qtbot.waitUntil(lambda: seen == [1, 3], timeout=2000)  # the latest value only


def test_throttle_with_a_phase_takes_its_turn_later(qtbot):
    seen = []
    th = Throttle(seen.append, interval_ms=60, phase_ms=40)
    th.request(1)
    th.request(2)
    assert seen == []  # a phase delays the first application of a burst
    qtbot.waitUntil(lambda: seen == [2], timeout=2000)
    th.request(3)
    th.flush()  # a pending value can be applied at once
    assert seen == [2, 3]
