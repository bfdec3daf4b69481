"""The crash's pictures (``nbst render CRASH.json``): the motion recorded from the crash file's
replay (:mod:`.motion`), the road and vehicles as solids (:mod:`.scene`), the readout
(:mod:`.readout`) and the video (:mod:`.video`). Importing it loads none of them."""
from __future__ import annotations

__all__: list[str] = []
