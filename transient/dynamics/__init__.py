"""The dynamics stage: a frozen system (reduced or full) with its critical step, one factory
per scheme that binds the step and owns its kernel's argument order, the chunks of steps a
run consumes, and one energy balance. Submodules are imported where used, so that reading a
history (`dynamics.energy`) does not compile kernels."""
