"""The `snowjax` command line.

Private: the public API is `snowjax.X`.
"""

from .app import main as main
