"""nbst.models.crash: the paper's second challenge, a multi-vehicle crash scripted and solved on MuJoCo.

Rooms, bottom up (the layer contract in pyproject.toml lists them):

* :mod:`.vehicle`: the built-in vehicle types (sedan, SUV, van) and their MuJoCo bodies;
* :mod:`.road`: the road layouts (straight, 4-way intersection, curve), curbs and barriers;
* :mod:`.scene`: a road and its vehicles as one MuJoCo model, with the contact sensors;
* :mod:`.checks`: the physics checks (braking, tilt table, restitution, the NCAP pulse).

Importing this package imports nothing heavy; the submodules that need MuJoCo import it.
"""
