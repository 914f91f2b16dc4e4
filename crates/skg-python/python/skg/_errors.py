"""The exceptions of skg. Each message is the text the ``skg-solve`` command line prints
after ``error:`` for the same mistake (file:line:column and all)."""


class Error(Exception):
    """Base class of every skg error."""


class SceneError(Error, ValueError):
    """The scene file, or an override (``set=``, ``nodes=``, ...), is invalid or cannot be
    read: an unknown key, a syntax error in an expression, an inadmissible initial state.
    The command line exits with status 1."""


class SolveError(Error, RuntimeError):
    """A solve could not be attempted or completed (the SBP operator on the grid, Ipopt
    itself, windows that do not fit). A solve that ran but did not converge or verify is
    not an error: see ``Solution.converged``, ``Solution.trusted`` and
    ``Solution.raise_for_status``."""


class FitError(Error, ValueError):
    """A fit cannot be attempted: a free parameter that is not one of the scene's, a
    starting value outside its bounds, or data that do not determine the parameters (the
    message says which combination is undetermined)."""


class IntegrationError(Error, RuntimeError):
    """A reference could not be computed: the integrator failed, the hard-wall reference
    does not model the scene, or the sample times are unusable."""


class SweepError(Error, RuntimeError):
    """A sweep file is invalid, its results cannot be read or written, or its workers
    cannot be started."""


class WorkerNotFound(SweepError, FileNotFoundError):
    """No ``skg-solve`` executable was found for a sweep's worker processes."""


class InputError(Error, ValueError):
    """A CSV file (trajectory, reference, a fit's data) cannot be read or used."""


class OutputError(Error, OSError):
    """An output file could not be written."""


class NotConverged(Error):
    """Raised by ``Solution.raise_for_status()`` for a solve that did not converge (the
    command line's exit status 3)."""


class NotVerified(Error):
    """Raised by ``Solution.raise_for_status()`` for a solve that converged but did not
    verify against time stepping (the command line's exit status 4)."""


class SolveWarning(UserWarning):
    """A warning of a solve (also recorded in ``summary["warnings"]``), e.g. a
    contact-episode count that differs from time stepping."""
