"""Continuum elastic-rod theory: the equilibria the bead simulations are checked against."""
