"""Classical contact, for comparison with third-medium contact: a penalty contact between named
boundaries on one displacement Newton (penalty_contact)."""
from ngtmc.classical.penalty_contact import PenaltyContact

__all__ = ['PenaltyContact']
