"""Fields: boundaries with holes, guidance lines and headlands from GeoJSON, WKT, GML, ISO 11783-10
TaskData, AgOpenGPS field folders and polygon CSVs, in one local metric frame (fields.field).

The names below are loaded on first use (PEP 562): the fields plugin registers its commands on
every start-up, ``--help`` included, without the readers.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from .first_use import loader

if TYPE_CHECKING:              # what static tools read; at run time __getattr__ loads each name
    from .field import (Field as Field, FieldError as FieldError, GuidanceLine as GuidanceLine,
                        choose_field as choose_field)
    from .readers import read_fields as read_fields

_HOME = {"Field": "field", "FieldError": "field", "GuidanceLine": "field", "choose_field": "field",
         "read_fields": "readers"}
__all__ = list(_HOME)

__getattr__ = loader(__name__, _HOME, globals())
