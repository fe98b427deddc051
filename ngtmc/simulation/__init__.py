"""The load-stepping loop (loop: Simulation), its records and history (records), its state, in-run
refinement, run options and plugins (Plugin, Progress)."""
