"""CS2 rounds from awpy's tables: an awpy 2 zip, a folder of awpy 3 tables, or a demo read
through awpy 3, into the same `Round` an ESTA file gives (decoy_cli/esta/awpy/reader.py)."""
