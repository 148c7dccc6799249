"""docs/config.md against the configuration reader: every documented key is
accepted where the page puts it, every documented default that is a TOML value
is the reader's default, and every key the resolved configuration holds is
documented.

The page's tables are read as written: a heading `## [section]` or
`### [[section.array]]`, then rows `| `key` | default | range | meaning |`.
A default that is a TOML value (a number, string, bool, array or inf) must
leave the resolved configuration unchanged when written explicitly; other
defaults ("(none)", "(derived)", "[floes] thickness") are prose, and for those
the test only checks that the key is known.
"""
import os
import re
import tomllib
import unittest

import floesim

SRC = os.environ["FLOESIM_SOURCE_DIR"]

# Keys that are read only in the company of others, and the company they need
# (each is documented so: "only with law = blend", "not with coriolis", ...).
CONTEXT = {
    ("coupling", "blend"): {"law": '"blend"'},
    ("coupling", "restitution"): {"law": '"blend"'},
    ("floes.floe", "mooring_damping"): {"mooring_period": "10.0"},
}
# What an array-of-tables entry needs before its other keys are read.
REQUIRED = {
    "floes.floe": 'vertices = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]',
    "fracture.load": 'point = [0.0, 0.0]\nforce = [1.0, 0.0]',
}


def documented():
    """{(section, key): default text}, with section "run", "sea.waves", "floes.floe" ..."""
    out, arrays = {}, set()
    section = None
    with open(os.path.join(SRC, "docs", "config.md")) as f:
        for line in f:
            m = re.match(r"^#{2,3} \[(\[?)([a-z_.]+)\]?\]\s*$", line)
            if m:
                section = m.group(2)
                if m.group(1):
                    arrays.add(section)
                continue
            if line.startswith("#"):
                section = None
                continue
            m = re.match(r"^\| `([a-z_]+)`( or `([a-z_]+)`)? \| ([^|]*) \|", line)
            if m and section:
                out[(section, m.group(1))] = m.group(4).strip()
                if m.group(3):
                    out[(section, m.group(3))] = m.group(4).strip()
    return out, arrays


def toml_value(text):
    """The default as a TOML value, or None when it is prose."""
    try:
        return tomllib.loads("x = " + text)["x"]
    except tomllib.TOMLDecodeError:
        return None


def document(section, arrays, key, value=None):
    """A TOML document setting [section] key = value, with what the key needs;
    value None: the same document without the key."""
    lines = [f"{k} = {v}" for k, v in CONTEXT.get((section, key), {}).items()]
    if section in arrays:
        # an entry's required keys, unless the key is one of them (force and impulse exclude each other)
        for l in REQUIRED[section].split("\n"):
            name = l.split(" ")[0]
            if name != key and not (key in ("force", "impulse") and name in ("force", "impulse")):
                lines.append(l)
    if value is not None:
        lines.append(f"{key} = {value}")
    head = f"[[{section}]]" if section in arrays else f"[{section}]"
    return head + "\n" + "".join(l + "\n" for l in lines)


def flatten(d, prefix=""):
    """{(section, key)} of a resolved configuration (arrays of tables by their entries)."""
    out = set()
    for k, v in d.items():
        if isinstance(v, dict):
            out |= flatten(v, f"{prefix}.{k}" if prefix else k)
        elif isinstance(v, list) and v and all(isinstance(e, dict) for e in v):
            for e in v:
                out |= flatten(e, f"{prefix}.{k}" if prefix else k)
        else:
            out.add((prefix, k))
    return out


class ConfigDocs(unittest.TestCase):
    def setUp(self):
        self.docs, self.arrays = documented()
        # the page has every table of the reader
        self.assertGreater(len(self.docs), 80)
        for s in ("run", "sea", "sea.waves", "sea.tank", "floes", "floes.floe", "contact", "coupling",
                  "forcing", "fracture", "fracture.load"):
            self.assertTrue(any(sec == s for sec, _ in self.docs), f"docs/config.md has no [{s}] table")

    def test_every_documented_key_is_known(self):
        for (section, key), default in self.docs.items():
            # a value of the wrong type: the reader must name the key's type, not call it unknown
            text = document(section, self.arrays, key, "{ wrong = 1 }")
            with self.subTest(key=f"[{section}] {key}"):
                with self.assertRaises(floesim.InputError) as e:
                    floesim.Config(text, name="docs.toml")
                self.assertNotIn("unknown key", str(e.exception))
                self.assertIn(key, str(e.exception))

    def test_documented_defaults_are_the_readers(self):
        checked = 0
        for (section, key), default in self.docs.items():
            if toml_value(default) is None:
                continue
            with self.subTest(key=f"[{section}] {key}", default=default):
                given = floesim.Config(document(section, self.arrays, key, default)).resolved()
                omitted = floesim.Config(document(section, self.arrays, key)).resolved()
                self.assertEqual(given, omitted)
            checked += 1
        self.assertGreater(checked, 60)

    def test_every_resolved_key_is_documented(self):
        # the defaults, and a configuration that sets the optional tables and keys
        full = floesim.Config(
            '[sea]\nmodel = "spectral"\n[sea.waves]\nkind = "regular"\namplitude = 0.1\nwavelength = 50.0\n'
            '[sea.tank]\nenabled = true\n'
            '[coupling]\nlaw = "blend"\nrestitution = 0.5\nstart = "given"\n'
            '[contact]\nbox = [0.0, 10.0, 0.0, 10.0]\n'
            '[[floes.floe]]\nvertices = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]\nheave = 0.1\nocean_drag = 1e-3\n'
            'mooring_period = 10.0\n'
            '[[fracture.load]]\npoint = [0.0, 0.0]\nimpulse = [1.0, 0.0]\n')
        keys = flatten(floesim.Config("").resolved()) | flatten(full.resolved())
        self.assertIn(("sea.tank", "rate"), keys)
        self.assertIn(("floes.floe", "mooring_damping"), keys)
        for section, key in sorted(keys):
            with self.subTest(key=f"[{section}] {key}"):
                self.assertTrue((section, key) in self.docs, f"[{section}] {key} is not in docs/config.md")


if __name__ == "__main__":
    unittest.main()
