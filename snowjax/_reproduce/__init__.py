"""`snowjax reproduce`: the thesis's figures and tables.

`registry.py` lists the figures (one line each) and runs them (`reproduce`); the figures
live in one module per thesis chapter (`chapter2.py`, `chapter3.py`, `chapter3_forces.py`,
`chapter4.py`) and in `terrain.py` (beyond the thesis); `spec.py` holds the `@figure`
decorator and the types a figure module uses, `plotting.py` and `output.py` the shared
helpers.

Private: the public API is `snowjax.X`.
"""
