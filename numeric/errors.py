"""Errors the numeric side raises for requests it refuses (the command prints one line, exits 2)."""


class RunRefused(ValueError):
    """A run that would be wrong or impossible, e.g. a step beyond Verlet's stability limit.

    Parameters
    ----------
    message : str
        Names the quantity (``dt``, ``method 'rk4'``, ``rtol``) in the library's words, never a
        command-line flag.
    quantity : str, optional
        The setting at fault (``"dt"``, ``"method"``, ``"steps"``, ``"rtol"``, ``"tol"``, ...); the
        command line uses it to name its flag.
    """

    def __init__(self, message: str, quantity: str | None = None):
        super().__init__(message)
        self.quantity = quantity
