"""What is computed: kernels, equation of state, pair terms, corrections, forces, integrators, time step, checks."""
