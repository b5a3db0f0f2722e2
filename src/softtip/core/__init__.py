"""Pure maths: fingertip geometry, the contact solution, spin torque, noise, depth, window fits."""
