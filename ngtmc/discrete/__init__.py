"""The discrete problem on a mesh: finite-element spaces and integration rules (spaces), the energy
forms (energy_forms, displacement_energy), the displacement Newton (newton), the phase field and its
dissipation, boundary conditions, the compiled-code cache, and the Solver that holds one scene's
discrete state."""
