"""Writing a ``.npz`` archive fast: each array stored or deflated by what compression would buy.

``numpy.savez_compressed`` deflates every array: on a result file most of the
bytes are the state and the kinematics, floating-point values that DEFLATE
shrinks by 5-10 % at ~25 MB/s, so compression was the most expensive part of a
save (0.29 s for a 9 MB result) for 17 % of its size. Here an array is deflated
only when that pays: integer, boolean and text arrays (kinds, candidates, the
header) and floating arrays in which at least half of the values repeat the one
before along the first axis (the zeros of a force out of contact, the onset
rates held between impacts: DEFLATE removes such runs at a high ratio); the
other arrays are stored. The archive is a standard ``.npz`` that
``numpy.load`` reads (members ``NAME.npy``), whatever each member's compression.
"""

from __future__ import annotations

import zipfile
from typing import BinaryIO, Mapping

import numpy as np

#: deflate a floating array when at least this fraction of its values repeat the previous row's
REPEATED_FRACTION = 0.5


def worth_deflating(array: np.ndarray) -> bool:
    """Whether DEFLATE pays for ``array`` (module docstring)."""
    if array.dtype.kind not in "fc":
        return True
    if array.ndim == 0 or array.shape[0] < 2:
        return False
    repeated = np.count_nonzero(array[1:] == array[:-1])
    return repeated >= REPEATED_FRACTION * (array.size - array.size // array.shape[0])


def write_npz(handle: BinaryIO, arrays: Mapping[str, np.ndarray], level: int = 1) -> None:
    """Write ``arrays`` as one ``.npz`` archive to the open binary ``handle`` (DEFLATE ``level`` where it pays)."""
    with zipfile.ZipFile(handle, mode="w", allowZip64=True, compresslevel=level) as archive:
        for name, value in arrays.items():
            array = np.asanyarray(value)
            # a member opened by name takes the archive's compression and level at that moment
            archive.compression = zipfile.ZIP_DEFLATED if worth_deflating(array) else zipfile.ZIP_STORED
            with archive.open(f"{name}.npy", mode="w", force_zip64=True) as member:
                np.lib.format.write_array(member, array, allow_pickle=False)
