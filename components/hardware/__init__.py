"""Helpers of the hardware I/O components: NMEA 0183 streams, the local geodetic frame, CAN
buses and the project's DBC (agrobot_tractor.dbc)."""
