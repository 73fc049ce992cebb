"""Newton loops whose live points swing between two values to the last iteration.

A batched Newton loop (all live points stepped at once, a point leaving
the batch once its step is small) is a function of the live set and the
live points' values: the same set at the same values (to the bit) steps
to the same values.  Near a root whose two neighbouring floats both give
steps of a few ulps, the points neither converge nor stop: they alternate
between two values for all the iterations left (a Barth mesh's skeleton
traces: 10 points for 13 of their 20 iterations).  Once the whole live
set is the one of the two iterations before and its values are those of
two iterations before, every later iteration repeats one of the last two:
the loop's result is known, and :class:`Swing` gives it at once.
"""

from __future__ import annotations

import numpy as np


class Swing:
    """Watch a batched loop for a two-cycle of its whole live set.

    Call :meth:`cycle` at the start of each iteration with the live
    indices and their values; where it returns values, those are what the
    live points hold after the last iteration: assign them and stop.
    """

    def __init__(self, iterations: int):
        self.iterations = iterations
        self.it = 0
        self.seen: list = []  # (live, values) at the start of the last two iterations

    def cycle(self, live: np.ndarray, values: np.ndarray) -> np.ndarray | None:
        """Values of the live points after the last iteration, if the loop is in a two-cycle, else None.

        Parameters
        ----------
        live : (K,) int64
            The indices of the points the iteration about to run steps.
        values : (K, ...) float64
            Their values before it (copied here).
        """
        values = np.array(values, dtype=float)
        out = None
        if len(self.seen) == 2:
            (live2, values2), (live1, values1) = self.seen
            if (np.array_equal(live, live2) and np.array_equal(live, live1)
                    and values.shape == values2.shape
                    and np.array_equal(values.view(np.int64), values2.view(np.int64))):
                # Iterations it, it+1, ... repeat it-2, it-1: after the
                # last one (index iterations - 1) the values are these
                # when an even number is left, the next ones otherwise.
                out = values if (self.iterations - self.it) % 2 == 0 else values1
        self.seen = (self.seen + [(np.array(live), values)])[-2:]
        self.it += 1
        return out
