"""The Python code blocks of docs/python.md run as written.

Each ```python block runs in one shared namespace, in order, from a temporary
folder that links the repository's examples/ and tests/ (so the documented
relative paths work and the files the examples write stay out of the source).
"""
import contextlib
import io
import os
import re
import tempfile
import unittest

SRC = os.environ["FLOESIM_SOURCE_DIR"]


class Docs(unittest.TestCase):
    def test_python_md_blocks_run(self):
        with open(os.path.join(SRC, "docs", "python.md")) as f:
            blocks = re.findall(r"```python\n(.*?)```", f.read(), re.S)
        self.assertGreaterEqual(len(blocks), 2)
        cwd = os.getcwd()
        with tempfile.TemporaryDirectory() as d:
            for sub in ("examples", "tests"):
                os.symlink(os.path.join(SRC, sub), os.path.join(d, sub))
            os.chdir(d)
            try:
                namespace = {}
                out = io.StringIO()
                for k, code in enumerate(blocks):
                    with contextlib.redirect_stdout(out):
                        exec(compile(code, f"docs/python.md block {k}", "exec"), namespace)
            finally:
                os.chdir(cwd)
        text = out.getvalue()
        # the first session: the run file holds the records from t = 6 s on
        self.assertIn("[ 6.  8. 10.] (3, 2, 12)", text)
        # the sweep: e = 1 keeps the energy of a frictionless impact, e = 0 loses some
        kept = {float(m[0]): float(m[1]) for m in re.findall(r"e = ([\d.]+): kinetic energy kept ([\d.]+)", text)}
        self.assertEqual(sorted(kept), [0.0, 0.5, 1.0])
        self.assertAlmostEqual(kept[1.0], 1.0, places=3)
        self.assertLess(kept[0.0], kept[0.5])
        self.assertLess(kept[0.5], kept[1.0])


if __name__ == "__main__":
    unittest.main()
