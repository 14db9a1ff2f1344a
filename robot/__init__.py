"""robot: closed-loop mechanisms on Pinocchio with clearance joints (see README.md)."""

import os

# The matrices here are small (tens of rows): multi-threaded BLAS only adds
# overhead on a loaded 2-core machine (a 90 x 180 product went from 30 to 200 us).
# Effective when robot is imported before numpy, as the scripts do.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
