"""What each WebSocket close code means, read from the comments of protocol/messages/."""

from __future__ import annotations

import inspect
import io
import tokenize

from protocol.messages import CloseCode

# The standard codes of RFC 6455 (section 7.4.1), for those the protocol module leaves
# uncommented; the application's own (4xxx) must say what they mean there.
RFC6455_MEANINGS = {
    1000: "normal closure: the connection has done its job",
    1008: "policy violation",
    1009: "a frame over the size limit",
}


def close_code_meanings() -> dict[CloseCode, str]:
    """Each close code's meaning: the comment on its line in protocol/messages/."""
    meanings: dict[CloseCode, str] = {}
    source = inspect.getsource(CloseCode)
    line_comments: dict[int, str] = {}
    names: dict[int, str] = {}
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        row = token.start[0]
        if token.type == tokenize.COMMENT:
            line_comments[row] = token.string.lstrip("# ").strip()
        elif token.type == tokenize.NAME and token.start[1] == 4 and row not in names:
            names[row] = token.string
    for row, name in names.items():
        if name in CloseCode.__members__ and row in line_comments:
            meanings[CloseCode[name]] = line_comments[row]
    for code in CloseCode:
        if code not in meanings and code in RFC6455_MEANINGS:
            meanings[code] = RFC6455_MEANINGS[code]
    missing = [code.name for code in CloseCode if code not in meanings]
    if missing:
        raise SystemExit(
            f"CloseCode members without a comment saying what they mean: {', '.join(missing)}"
        )
    return meanings
