"""The MuJoCo MJX bridge behind `snowjax.mjx` (optional extra `snowjax[mjx]`)."""
