"""Continuum reference for RFEM links: each flexible link as a geometrically exact beam.

Every other engine of the harness receives the RFE-discretised model, so none can see a
wrong discretisation.  Here the same machine is rebuilt in Exudyn with each flexible link
as a mesh of ObjectBeamGeometricallyExact elements (Simo-Reissner rod: axial, two shear
and torsion strains, two curvatures; linear elements on Euler-parameter nodes) carrying
the section's own E A, k G A, G J, E I_y, E I_z, rho A and rho I, and the rigid links as
rigid bodies joined by Exudyn's generic joints (redundant coordinates, index-3
generalized-alpha).  Modules:

* :mod:`.section`: the beam's continuum section data from its material and section
  constants (shear coefficients after Cowper 1966);
* :mod:`.layout`: a gpme model split into rigid bodies, joints and beams (pure numpy);
* :mod:`.system`: the Exudyn items;
* :mod:`.runs`: runs of a scenario on both sides and the quantities that mean the same in
  both (tip position, elastic tip deflection and rotation, rigid joint coordinates,
  multipliers of the programmed constraints).
"""
