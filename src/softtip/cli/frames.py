"""The paragraph on frames and units that ends the help of the ``softtip`` group and of the
commands that read or write vectors; a module of its own so that ``softtip --help`` and
``softtip --version`` import neither the estimator nor the fingertips."""

FRAMES_HELP = """\
Frames and units: every vector is in the sensor frame (origin at the F/T sensor's
measuring point, z along the finger axis toward the tip, right-handed). Inside and in
every file softtip uses SI: N, N·m, m, s; angles are degrees in files and plots. f and m
are the force and moment the touched object exerts on the fingertip, moment about the
sensor origin; in contact f pushes into the fingertip.
"""
