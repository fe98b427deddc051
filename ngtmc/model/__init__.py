"""The equations of the model, free of any mesh: hyperelastic materials and their energies (materials),
the AT-2 fracture energy and degradation (fracture), the third-medium contact regulariser
(regularisation), and the tension/compression splits of the strain energy (splits)."""
