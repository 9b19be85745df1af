"""Realistic-but-perturbed files: a valid file, then a few edits of the kinds users and
half-finished tools make (a truncated line, a column too many or too few, NaN/inf, huge
numbers, unicode, duplicated or unknown keys, values of the wrong type, an empty file, bytes
that are not text). Shared by the tests of each file type; each passes its own valid texts
and the tokens that are wrong for its format.
"""

from __future__ import annotations

from hypothesis import strategies as st

# Tokens that stand in for a value or a name: each is wrong somewhere.
COMMON_TOKENS = (
    "nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1e308", "-1e308", "1e400", "1e-400",
    "9" * 40, "-" + "9" * 40, "9" * 5000, "0x10", "1_000", "+", "-", ".", "1.2.3", "",
    "true", "false", "\"text\"", "[1, 2]", "{}", "é", "\u202eRTL", "名前", "\x00", "\t",
    "0", "-0", "1", "-1", "3", "65535", "4294967296", "2147483648", "-2147483649",
    "#", ",", "=", "[", "]", "\"", "'", "\\",
)


@st.composite
def perturbed(draw, valid_texts: tuple[str, ...], tokens: tuple[str, ...] = (),
              header_lines: int = 0) -> bytes:
    """One of valid_texts with 0..4 edits, as bytes (some edits are not UTF-8).

    header_lines: in half the examples the first lines (a format's header) are left alone,
    so most files get past the header and the edits reach the values behind it."""
    text = draw(st.sampled_from(valid_texts))
    lines = text.splitlines()
    keep = header_lines if draw(st.booleans()) else 0
    pool = COMMON_TOKENS + tuple(tokens)
    token = st.one_of(st.sampled_from(pool), st.text(max_size=12))
    for _ in range(draw(st.integers(0, 4))):
        # replace_field three times: a wrong value in a well-formed line reaches the checks
        # behind the parser (ranges, NaN, sequence), where structural edits stop at the parser.
        kind = draw(st.sampled_from((
            "truncate", "drop_field", "add_field", "replace_field", "replace_field",
            "replace_field", "duplicate_line", "delete_line", "insert_line", "swap_lines",
            "empty", "separator")))
        if len(lines) <= keep:
            lines.append(draw(token))
            continue
        i = draw(st.integers(keep, len(lines) - 1))
        fields = lines[i].split()
        if kind == "truncate":
            lines[i] = lines[i][:draw(st.integers(0, len(lines[i])))]
        elif kind == "drop_field" and fields:
            del fields[draw(st.integers(0, len(fields) - 1))]
            lines[i] = " ".join(fields)
        elif kind == "add_field":
            fields.insert(draw(st.integers(0, len(fields))), draw(token))
            lines[i] = " ".join(fields)
        elif kind == "replace_field" and fields:
            fields[draw(st.integers(0, len(fields) - 1))] = draw(token)
            lines[i] = " ".join(fields)
        elif kind == "duplicate_line":
            lines.insert(i, lines[i])
        elif kind == "delete_line":
            del lines[i]
        elif kind == "insert_line":
            lines.insert(i, " ".join(draw(st.lists(token, max_size=4))))
        elif kind == "swap_lines":
            j = draw(st.integers(keep, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif kind == "empty":
            lines = lines[:keep]
        elif kind == "separator":
            lines[i] = lines[i].replace(" ", draw(st.sampled_from(("\t", ",", ", ", "  ", ""))))
    data = "\n".join(lines).encode("utf-8", "surrogatepass")
    if draw(st.integers(0, 9)) == 0:      # a byte that is not UTF-8 (a Latin-1 editor, a bad copy)
        at = draw(st.integers(0, len(data)))
        bad = draw(st.sampled_from((b"\xff", b"\xe9", b"\xc3", b"\x80\x80")))
        data = data[:at] + bad + data[at:]
    return data
