"""softtip: intrinsic tactile sensing with a soft fingertip on a six-axis F/T sensor."""

__version__ = "0.1.0"
