"""Integer codes shared by the kernels and the stages that pack their arrays; plain constants,
so a case loads and its signals and laws are packed without importing Numba."""

# signal kinds (case.signals) and the columns of their parameter rows; FREQUENCY holds the
# sine's frequency and the chirp's f0
CONSTANT, STEP, IMPULSE, SINE, CHIRP, TABLE = range(6)
START, AMPLITUDE, DURATION, RISE, FREQUENCY, F1, PHASE = range(7)
N_PARAMS = 8

# contact laws (kernels.laws)
EXPONENTIAL, LINEAR, BILATERAL = 0, 1, 2

# friction laws (kernels.friction): the regularized sign of the sliding velocity; FRICTIONLESS
# marks the points of a pair without friction
TANH, ATAN, FRICTIONLESS = 0, 1, -1

# status of a chunk of steps (kernels.stepping, kernels.newmark)
OK, NOT_FINITE, NO_CONVERGENCE = 0, 1, 2

# the energy terms of an output row, in their column order (kernels.stepping)
KINETIC, STRAIN, CONTACT, WORK, DISSIPATED = range(5)
ENERGY_TERMS = ("kinetic", "strain", "contact", "external_work", "dissipated")
