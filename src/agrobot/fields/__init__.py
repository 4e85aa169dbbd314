"""Fields: boundaries with holes, guidance lines and headlands from GeoJSON, WKT, GML, ISO 11783-10
TaskData, AgOpenGPS field folders and polygon CSVs, in one local metric frame (fields.field)."""
from .field import Field, FieldError, GuidanceLine, choose_field
from .readers import read_fields

__all__ = ["Field", "FieldError", "GuidanceLine", "choose_field", "read_fields"]
