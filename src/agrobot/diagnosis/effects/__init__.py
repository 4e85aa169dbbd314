"""The diagnosis catalogue, one effect per module: each module defines one ``Effect`` subclass
(diagnosis.effect); ``diagnosis.catalogue`` collects them."""
