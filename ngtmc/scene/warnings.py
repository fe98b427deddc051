"""The warnings a scene raises when its inputs are served, but not exactly or not plausibly."""

__all__ = ["ResolutionWarning", "ElementWarning", "ScaleWarning"]


class ResolutionWarning(UserWarning):
    """The mesh does not resolve the phase-field length scale where fracture may happen."""


class ElementWarning(UserWarning):
    """The elements of the mesh cannot be served exactly: curved elements (``mesh.Curve(k)``) of a
    higher order k than the displacement's, where a homogeneous deformation is not reproduced
    (the patch test fails: tests/test_verification.py)."""


class ScaleWarning(UserWarning):
    """A scene's number lies outside what is plausible in mm, N and MPa (:mod:`ngtmc.scene.scale`);
    ``Scene(scale_check=False)`` silences it for that scene."""
