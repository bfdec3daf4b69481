"""nbst.render: headless moderngl rendering of a choreography to frames, MP4/GIF
video, and matplotlib figures in the manner of the paper.

Imported as ``nbst.render``: ``nbst/render`` is a link to this folder, in the checkout and installed alike.
Importing it does not import moderngl or imageio; the submodules that need them do.
"""
