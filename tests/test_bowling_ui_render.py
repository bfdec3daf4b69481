"""The pin-deck close-up camera (render/bowling/lane.py, ``--camera deck``): the whole rack in the
frame, the head pin in front, drawn where the camera projects it; the readout names the result."""
from __future__ import annotations

import numpy as np
import pytest

from nbst.models.bowling import lane, scene
from nbst.render.bowling import lane as bl
from nbst.render.bowling import throw as bt

SIZE = (640, 360)
TYPICAL = lane.Delivery(hand="right", board=20, at="foul", angle=2.82, mph=17, rpm=350, rotation=45, tilt=12)


@pytest.fixture(scope="module")
def deck():
    from nbst.render.core.gl import create_context

    ctx = create_context()
    th = bt.record_throw(TYPICAL, "house")
    r = bl.LaneRenderer(ctx, th, size=SIZE, camera="deck")
    yield r, th
    r.release()
    ctx.release()


def test_the_deck_camera_frames_the_whole_rack_with_the_head_pin_in_front(deck):
    r, _ = deck
    vp, vpm, eye, cam = r.views(0.0)[0]
    assert cam == "deck" and eye[0] < 0.0 < eye[2]          # in front of the pins, above the deck
    px = {n: r.to_pixel(vp, vpm, [x, y, 0.19], SIZE[1]) for n, (x, y) in zip(scene.PIN_NUMBERS, scene.pin_spots())}
    for n, (col, row, front) in px.items():
        assert front and 0 <= col < SIZE[0] and 0 <= row < SIZE[1], n
    assert px[1][1] > px[5][1] > px[8][1]                     # rows: nearer is lower on the screen
    assert px[7][0] < px[10][0]                               # the 7 on the left, the 10 on the right


def test_the_deck_still_draws_the_head_pin_where_it_stands_and_names_the_result(deck):
    r, th = deck
    img = r.render(0.0)
    col, row, _ = r.to_pixel(*r.views(0.0)[0][:2], [0.0, 0.0, 0.19], SIZE[1])
    rgb = img[int(round(row)), int(round(col))].astype(int)
    assert rgb.min() > 70 and np.ptp(rgb) < 10                # the pin: a neutral grey-white, not wood, pit or kickback
    text = "\n".join(r.readout(float(th.motion.times[-1])))
    assert "result  down" in text and "named   " in text and "sample" in text
