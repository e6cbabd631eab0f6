"""The layout of the state the kernels update in place: its rows and the accumulators' slots,
one definition each (dynamics.state names them for the stages); plain constants, read by the
kernels as compile-time ones."""

# the state's rows, (STATE_ROWS, n): displacement, velocity, acceleration, the time (in
# [TIME_ROW, 0]), the forces at the start of the previous step and of the next (the exponential
# scheme carries them between chunks), the friction force at the next step's start
Q_ROW, V_ROW, A_ROW, TIME_ROW, FORCES_ROW, START_ROW, FRICTION_ROW = range(7)
STATE_ROWS = 7

# the accumulators, (ACC_SLOTS,): the external work and the dissipated energy so far [J], the
# damping power explicit_full carries, the sliding's input power at the step's start [W]
WORK_ACC, DISSIPATED_ACC, DAMPING_ACC, SLIDING_ACC = range(4)
ACC_SLOTS = 4
