"""Identification: fork spring and damper from dyno records, tire values by the coefficient of
restitution, chosen model parameters from a sled drop record. ``identify`` is the one entry
point; each part lives in its own module (``spring``, ``damper``, ``tire``, ``dropfit``) with its
synthetic-record generator (``dyno_synthetic``, ``tire_synthetic``, ``drop_synthetic``)."""
from mtbmj.identify.fitresult import FitResult
from mtbmj.measured.records import Record, RecordError, read_record
from mtbmj.identify.run import Identification, identify

__all__ = ["identify", "Identification", "FitResult", "Record", "RecordError", "read_record"]
