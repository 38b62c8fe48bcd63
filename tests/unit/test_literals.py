"""Every literal form of IEC 61131-3 and the value it must produce."""

import pytest

from iec2kmod.parse.literals import LiteralError, classify, days_from_civil

NS_S = 1_000_000_000


@pytest.mark.unit
@pytest.mark.parametrize("text, kind, value, type_name", [
    ("0", "int", 0, None),
    ("1_000_000", "int", 1000000, None),
    ("16#FF", "int", 255, None),
    ("16#ff_ff", "int", 65535, None),
    ("2#1010_1010", "int", 170, None),
    ("8#17", "int", 15, None),
    ("INT#5", "int", 5, "INT"),
    ("int#-5", "int", -5, "INT"),
    ("DINT#16#7FFF_FFFF", "int", 0x7FFFFFFF, "DINT"),
    ("BOOL#1", "int", 1, "BOOL"),
    ("BOOL#TRUE", "bool", True, "BOOL"),
    ("TRUE", "bool", True, None),
    ("false", "bool", False, None),
    ("3.14", "real", 3.14, None),
    ("1.0E-3", "real", 1.0e-3, None),
    ("1_000.5e+2", "real", 100050.0, None),
    ("2E3", "real", 2000.0, None),
    ("REAL#1.5", "real", 1.5, "REAL"),
    ("LREAL#-2.5", "real", -2.5, "LREAL"),
    ("T#1h2m3s4ms", "time", (3600 + 120 + 3) * NS_S + 4_000_000, "TIME"),
    ("TIME#-5s", "time", -5 * NS_S, "TIME"),
    ("T#1.5s", "time", 1_500_000_000, "TIME"),
    ("t#100ms", "time", 100_000_000, "TIME"),
    ("T#2d_3h", "time", (2 * 86400 + 3 * 3600) * NS_S, "TIME"),
    ("T#10us", "time", 10_000, "TIME"),
    ("T#7ns", "time", 7, "TIME"),
    ("LTIME#1m", "time", 60 * NS_S, "LTIME"),
    ("D#2024-02-29", "date", days_from_civil(2024, 2, 29) * 86400 * NS_S, "DATE"),
    ("DATE#1970-01-01", "date", 0, "DATE"),
    ("TOD#12:30:15.5", "tod", (12 * 3600 + 30 * 60 + 15) * NS_S + 500_000_000, "TOD"),
    ("TIME_OF_DAY#00:00:01", "tod", NS_S, "TOD"),
    ("DT#1970-01-02-00:00:01", "dt", 86401 * NS_S, "DT"),
    ("DATE_AND_TIME#2000-01-01-12:00:00", "dt",
     (days_from_civil(2000, 1, 1) * 86400 + 12 * 3600) * NS_S, "DT"),
    ("'abc'", "string", "abc", None),
    ("'it$'s'", "string", "it's", None),
    ("'$N$L$R$T$P$$'", "string", "\n\n\r\t\f$", None),
    ("'$41$0A'", "string", "A\n", None),
    ('"wide $0041"', "wstring", "wide A", None),
    ("STRING#'x'", "string", "x", "STRING"),
    ("Color#Red", "enum", "Red", "Color"),
])
def test_literal_forms(text, kind, value, type_name):
    k, v, t = classify(text)
    assert (k, t) == (kind, type_name)
    if kind == "real":
        assert v == pytest.approx(value)
    else:
        assert v == value


@pytest.mark.unit
@pytest.mark.parametrize("text, message", [
    ("D#2023-02-29", "day 29 out of range 1..28"),
    ("D#2023-13-01", "month 13 out of range 1..12"),
    ("TOD#24:00:00", "time of day out of range"),
    ("'bad $Q escape'", "invalid escape '$Q'"),
    ("2#102", "invalid digits for base 2"),
])
def test_bad_literals(text, message):
    with pytest.raises(LiteralError, match=message.replace("$", r"\$").replace("(", r"\(")):
        classify(text)
