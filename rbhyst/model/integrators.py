"""The integrators by name, as a deck gives them (rbhyst.solve.integrators implements each).
Plain names: the compiled kernels' build imports this without the deck's dependencies."""

#: the default first
INTEGRATORS = ("chang", "central-difference", "newmark", "kr-alpha", "reference", "adaptive")
