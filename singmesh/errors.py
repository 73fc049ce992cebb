"""The exception raised for input singmesh cannot mesh."""


class SurfaceError(ValueError):
    """Bad input: the text is not a usable polynomial, or the box is not a box.

    The message names the problem (syntax error and its position, unknown
    symbol, non-polynomial function, zero polynomial, non-finite
    coefficient, degree over the limit, empty or inverted box).
    """
