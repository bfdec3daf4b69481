"""nbst.render: headless moderngl rendering of a choreography to frames, MP4/GIF
video, and matplotlib figures in the manner of the paper.

Installed as ``nbst.render`` (setuptools ``package-dir`` maps this folder).
Importing it does not import moderngl or imageio; the submodules that need them do.
"""
