"""Bowling's pictures: the 5 m throw on the pin deck (:mod:`.deck`, ``nbst render THROW.json``),
the foul-line throw recorded (:mod:`.throw`) and filmed down the full lane (:mod:`.lane`,
``nbst bowl frame --video``), and the ball's path plot (:mod:`.path`). Importing it loads none of
them."""
from __future__ import annotations

__all__: list[str] = []
