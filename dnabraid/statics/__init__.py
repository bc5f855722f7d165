"""Zero-temperature bead solvers: bead rods relaxed to mechanical equilibrium.

* :mod:`.newton`: the damped Newton minimiser with saddle escape, and the sparse Hessian
  blocks (pairs, hinges) the problems share.
* :mod:`.open_knot`: an open (2, 2n+1) knot in a rod pulled at both ends, against the
  continuum knot (Audoly, Clauvelin & Neukirch 2007; Jawed et al. 2015).
* :mod:`.closed_braid`: closed braids, torus links and knots in hard contact, against the
  closed ply (Starostin & van der Heijden 2014).
"""
