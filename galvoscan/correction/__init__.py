"""Field-distortion correction on the host side: tables from the 003 f-theta model, from
measured points and photos (004), and from lens files; the study the README reports.

The table itself, and the exact arithmetic the gateware applies, are
:class:`galvoscan.gateware.field.correction_table.CorrectionTable`.
"""
