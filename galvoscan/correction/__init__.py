"""Field-distortion correction on the host side: tables from the f-theta model of Liao & Chen
2016, from measured points and photos (Zhu & Zhang), and from lens files; the study the docs
report (docs/user/correction.md).

The table itself, and the exact arithmetic the gateware applies, are
:class:`galvoscan.gateware.field.correction_table.CorrectionTable`.
"""
