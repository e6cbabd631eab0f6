"""Settings of the whole suite."""
import os

# The suite's two workers compile the same kernels and wait on each other's compile lock; the
# line that says such a wait (transient.jit) would land on a stderr that tests hold to one line
# 'error: ...' or to nothing. tests/test_jit.py sets it back to test that line.
os.environ.setdefault("TRANSIENT_LOCK_NOTICE_S", "inf")

# the suite runs as the command line does, with the settings that speed it up (an import
# alone makes none: tests/test_configure.py)
import transient  # noqa: E402

transient.configure()
