"""Rust source to tokens: comments, strings and char literals blanked first."""

import re

_SPECIAL = re.compile(r"""//|/\*|["']|\b(?:br|cr|r|b|c)(?=["'#])""")


def _char_literal_end(text, j):
    """End (exclusive) of the char literal opening at text[j] == "'", or -1
    where the quote opens a lifetime or a label ('a, 'outer:)."""
    n = len(text)
    if j + 1 < n and text[j + 1] == "\\":
        e = text.find("'", j + 3)  # '\'' : the escaped char is at j + 2
        return n if e < 0 else e + 1
    if j + 2 < n and text[j + 2] == "'" and text[j + 1] != "\n":
        return j + 3
    return -1


def strip_rust(text):
    """Blank comments, strings and char literals; keep every newline.

    Returns (clean, strings): each string literal becomes `"` newlines `"` in
    clean, and strings maps the offset of its opening quote in clean to the
    literal's raw text (for `#[path = "..."]` and `include!("...")`)."""
    out, strings = [], {}
    olen = 0
    i, n = 0, len(text)

    def put(s):
        nonlocal olen
        out.append(s)
        olen += len(s)

    while True:
        m = _SPECIAL.search(text, i)
        if not m:
            put(text[i:])
            break
        j, tok = m.start(), m.group()
        put(text[i:j])
        if tok == "//":  # line, doc and inner-doc comments
            e = text.find("\n", j)
            put(" ")
            i = n if e < 0 else e
            continue
        if tok == "/*":  # block comments nest
            depth, k = 1, j + 2
            while k < n and depth:
                if text.startswith("/*", k):
                    depth, k = depth + 1, k + 2
                elif text.startswith("*/", k):
                    depth, k = depth - 1, k + 2
                else:
                    k += 1
            put(" " + "\n" * text.count("\n", j, k))
            i = k
            continue
        if tok == "'":
            e = _char_literal_end(text, j)
            if e < 0:
                put("'")  # a lifetime: the tokenizer reads 'a whole
                i = j + 1
            else:
                put(" 0 ")
                i = e
            continue
        k = j if tok == '"' else j + len(tok)  # past a b / c / r / br / cr prefix
        if tok == "b" and text[k] == "'":  # byte literal b'x'
            e = _char_literal_end(text, k)
            if e >= 0:
                put(" 0 ")
                i = e
                continue
        if "r" in tok:
            h = k
            while h < n and text[h] == "#":
                h += 1
            if h >= n or text[h] != '"':  # a raw identifier r#name, not a string
                put(text[j:h])
                i = h
                continue
            close = '"' + "#" * (h - k)
            e = text.find(close, h + 1)
            e = n if e < 0 else e
            content, i = text[h + 1:e], e + len(close)
        elif text[k] == '"':
            e = k + 1
            while e < n and text[e] != '"':
                e += 2 if text[e] == "\\" else 1
            content, i = text[k + 1:e], e + 1
        else:  # b# or c#: no literal
            put(text[j:k])
            i = k
            continue
        strings[olen] = content
        put('"' + "\n" * content.count("\n") + '"')
    return "".join(out), strings


_TOKEN = re.compile(r"""
    (?P<nl>\n)
  | (?P<ws>[^\S\n]+)
  | (?P<lt>'(?:r\#)?[^\W\d]\w*)
  | (?P<id>(?:r\#)?[^\W\d]\w*)
  | (?P<num>\d\w*)
  | (?P<str>"[^"]*")
  | (?P<p>::|.)
""", re.X)

KEYWORDS = frozenset("""
    as async await box break const continue crate do dyn else enum extern false fn
    for if impl in let loop match mod move mut pub ref return self Self static
    struct super trait true try type unsafe use where while yield
""".split())

# Keywords after which an identifier is declared, not referred to.
DECLARES = frozenset("fn struct enum union trait type const static let mut mod as".split())


def tokenize(text):
    """(kind, value, line) triples of stripped Rust. kind: 'id' (a raw
    identifier is an id without its r#), 'kw', 'lt', 'num', 'str' (value: the
    literal's text), 'p' (punctuation; '::' is one token)."""
    clean, strings = strip_rust(text)
    toks, line = [], 1
    for m in _TOKEN.finditer(clean):
        kind, v = m.lastgroup, m.group()
        if kind == "nl":
            line += 1
        elif kind == "ws":
            continue
        elif kind == "str":
            toks.append(("str", strings.get(m.start(), ""), line))
            line += v.count("\n")
        elif kind == "id":
            if v.startswith("r#"):
                toks.append(("id", v[2:], line))
            else:
                toks.append(("kw" if v in KEYWORDS else "id", v, line))
        else:
            toks.append((kind, v, line))
    return toks
