"""docs/formats.md against the run files floesim writes: every dataset of a
run file, and every object of its checkpoint, is documented on that page.

Short runs that between them write every optional part: a spectral sea with
floes and the implicit integrator with moving footprints (sea, incident waves,
the floe-sea state), collisions recorded, a jam against a wall (its warm
starts), and a percussion that splits floes (fracture events). Each run ends
with a checkpoint. The page's tables name datasets in backquotes, several to a
cell (`/floes/thickness`, `/floes/mass`); in the checkpoint's table a name
without a folder (`density` after `floes/thickness`) is in the folder of the
cell's first name.
"""
import os
import re
import tempfile
import unittest

import h5py

import floesim

SRC = os.environ["FLOESIM_SOURCE_DIR"]


def documented(section_title):
    """Names in backquotes in the first column of the tables of one section of
    docs/formats.md (from its heading to the next heading of the same level or above)."""
    with open(os.path.join(SRC, "docs", "formats.md")) as f:
        text = f.read()
    m = re.search(r"^(#+) " + re.escape(section_title) + r".*$", text, re.M)
    assert m, f"docs/formats.md has no section '{section_title}'"
    level = len(m.group(1))
    rest = text[m.end():]
    end = re.search(r"^#{1,%d} " % level, rest, re.M)
    body = rest[: end.start()] if end else rest
    names = set()
    for line in body.splitlines():
        if not line.startswith("| `"):
            continue
        cell = line.split("|")[1]
        folder = None
        for name in re.findall(r"`([^`]+)`", cell):
            if "/" in name.strip("/"):
                folder = name.rsplit("/", 1)[0]
            elif folder is not None and not name.startswith("/"):
                name = folder + "/" + name
            names.add(name.strip("/"))
    return names


def datasets(path):
    """Every dataset and group of a file, as paths without the leading '/'."""
    out = set()
    with h5py.File(path, "r") as f:
        f.visit(out.add)
        kinds = {name: isinstance(f[name], h5py.Dataset) for name in out}
    return kinds


class FormatsDocs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        d = cls.tmp.name
        cls.files = []

        def run(cfg, name, until):
            out = os.path.join(d, name + ".h5")
            floesim.Simulation(cfg).run(out, until=until)
            cls.files.append(out)

        sea = floesim.Config.load(os.path.join(SRC, "tests", "regression", "floes_on_sea.toml"))
        sea["run"]["threads"] = 1
        sea.update({"coupling": {"integrator": "implicit", "footprint_reach": 0.25}})
        run(sea, "sea_implicit", 0.5)

        collide = floesim.Config.load(os.path.join(SRC, "tests", "regression", "two_floes_collide.toml"))
        collide["run"]["threads"] = 1
        collide["run"]["record_collisions"] = True
        run(collide, "collide", collide["run"]["t_end"])

        wall = floesim.Config.load(os.path.join(SRC, "examples", "pack_against_wall.toml"))
        wall["run"]["threads"] = 1
        run(wall, "wall", 600.0)

        split = floesim.Config.load(os.path.join(SRC, "examples", "percussion.toml"))
        split["run"]["threads"] = 1
        run(split, "percussion", split["run"]["t_end"])

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_every_dataset_is_documented(self):
        results = documented("Run file")
        checkpoint = documented("Checkpoint and restart")
        self.assertIn("floes/state", results)
        self.assertIn("floes/density", checkpoint)  # a name in the folder of its cell's first name
        seen = set()
        for path in self.files:
            for name, is_dataset in datasets(path).items():
                seen.add(name)
                with self.subTest(file=os.path.basename(path), dataset=name):
                    if name.startswith("checkpoint/"):
                        inner = name[len("checkpoint/"):]
                        # a group is documented through its members
                        if is_dataset:
                            self.assertTrue(inner in checkpoint,
                                            f"/{name} is not in docs/formats.md, 'Checkpoint and restart'")
                    elif is_dataset:
                        self.assertTrue(name in results, f"/{name} is not in docs/formats.md, 'Run file'")
        # the runs wrote the optional parts they are here for
        for part in ("sea/eta", "events/collisions", "events/fracture", "checkpoint/warm_start/keys",
                     "checkpoint/floe_sea/footprint_reference", "checkpoint/floe_sea/mean_horizontal"):
            self.assertIn(part, seen)


if __name__ == "__main__":
    unittest.main()
