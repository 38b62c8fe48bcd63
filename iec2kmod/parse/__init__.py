"""The front end: the grammar (grammar/iec61131.tx), the textX parser and
its AST builder (parser.py), the hand-written ST statement parser
(stfast.py), literal classification (literals.py), the lexical rules
and the pragma registry (lexical.py) and the driver that
parses and checks a project (frontend.py: run, collect_files)."""
