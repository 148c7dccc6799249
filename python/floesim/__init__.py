"""floesim from Python: configurations, simulations and run files.

    import floesim
    cfg = floesim.Config.load("examples/floes_on_waves.toml")
    cfg["run"]["t_end"] = 600              # checked at once, like `floesim run` would
    sim = floesim.Simulation(cfg)
    sim.run_until(120.0)                   # lands on the output times, as `floesim run`
    sim.state                              # (n, 12) array, columns floesim.STATE_COLUMNS
    sim.energies()                         # {"floes_horizontal_kinetic": ..., "total": ...}
    run = floesim.read_run("out.h5")       # run.time, run.state [T, n, 12], run.energy

Bad input raises floesim.InputError (a ValueError) and a failed run
floesim.RunError (a RuntimeError), with the messages of the command line.
docs/python.md describes everything.
"""

import copy
import os
import re

import numpy as np

from . import _floesim
from ._floesim import COLLISION_EVENT_COLUMNS, FRACTURE_EVENT_COLUMNS, LCP_COLUMNS, STATE_COLUMNS, InputError, RunError, __version__

__all__ = ["Config", "Simulation", "RunFile", "read_run", "compare_runs", "InputError", "RunError",
           "STATE_COLUMNS", "LCP_COLUMNS", "FRACTURE_EVENT_COLUMNS", "COLLISION_EVENT_COLUMNS",
           "__version__"]


def _frozen(value):
    """Arrays come back as tuples (nested for nested arrays): assign a new value to change one."""
    if isinstance(value, list):
        return tuple(_frozen(v) for v in value)
    return value


def _is_table_array(value):
    return isinstance(value, list) and len(value) > 0 and all(isinstance(v, dict) for v in value)


def _merge(into, changes):
    for key, value in changes.items():
        if isinstance(value, dict) and isinstance(into.get(key), dict):
            _merge(into[key], value)
        else:
            into[key] = copy.deepcopy(value)


class Config:
    """A run configuration (docs/config.md): the TOML document, always valid.

    Reading a key gives the value in force: the document's, else the default.
    Writing one (``cfg["run"]["t_end"] = 10``) checks the whole configuration
    as `floesim run` does; a bad key or value raises InputError naming the key
    and leaves the configuration as it was. Tables read as views that write
    through; arrays read as tuples (assign a new list to change one).
    """

    def __init__(self, text="", *, name="<string>", base_dir=None):
        """A configuration from TOML text; relative paths in it (pack, series)
        are taken from base_dir (default: the current folder)."""
        self._name = str(name)
        self._base_dir = os.path.abspath(base_dir if base_dir is not None else os.getcwd())
        self._text = text            # the text as given, checked with its own line numbers
        self._resolved = _floesim.check_config(text, self._name, self._base_dir)
        self._doc = _floesim.toml_to_dict(text, self._name)
        self._resolved_doc = None

    @classmethod
    def load(cls, path):
        """Reads a configuration file (relative paths inside are relative to its folder)."""
        path = os.fspath(path)
        with open(path, encoding="utf-8") as f:
            text = f.read()
        return cls(text, name=path, base_dir=os.path.dirname(os.path.abspath(path)))

    # -- reading and writing keys ------------------------------------------

    def __getitem__(self, section):
        return _Table(self, ())[section]

    def __setitem__(self, section, value):
        _Table(self, ())[section] = value

    def __delitem__(self, section):
        del _Table(self, ())[section]

    def __contains__(self, section):
        return section in _Table(self, ())

    def keys(self):
        return _Table(self, ()).keys()

    def update(self, changes):
        """Merges nested dicts of changes into the document and checks once:
        for changes that are only valid together (e.g. a sea model and its waves)."""
        doc = copy.deepcopy(self._doc)
        _merge(doc, changes)
        self._replace(doc)

    def add_floe(self, vertices, **keys):
        """Appends an inline floe ([[floes.floe]]): vertices [[x, y], ...] (m) and
        any of its keys (velocity, angular_velocity, thickness, density, static, ocean_drag)."""
        doc = copy.deepcopy(self._doc)
        floes = doc.setdefault("floes", {}).setdefault("floe", [])
        floes.append({"vertices": np.asarray(vertices, dtype=float).tolist(), **keys})
        self._replace(doc)

    # -- whole documents ----------------------------------------------------

    def to_dict(self):
        """The document as written (nested dicts and lists), without defaults."""
        return copy.deepcopy(self._doc)

    def toml(self):
        """The document as TOML text (the original text while unmodified)."""
        return self._text

    def resolved(self):
        """Every key with its value in force, as nested dicts (paths made absolute)."""
        return copy.deepcopy(self._resolved_dict())

    def resolved_toml(self):
        """The resolved configuration as TOML: what a run file records as its `config`."""
        return self._resolved

    def copy(self):
        return copy.deepcopy(self)

    @property
    def name(self):
        return self._name

    @property
    def base_dir(self):
        return self._base_dir

    def __repr__(self):
        return f"floesim.Config({self._name!r})"

    # -- internals ----------------------------------------------------------

    def _resolved_dict(self):
        if self._resolved_doc is None:
            self._resolved_doc = _floesim.toml_to_dict(self._resolved, self._name)
        return self._resolved_doc

    def _call(self, fn, *args, text=None):
        """Calls fn(text, name, base_dir, *args) on the document's text. Messages
        about a document changed from Python lose their line numbers, which
        would point into regenerated text rather than into the file."""
        modified = self._modified or text is not None
        try:
            return fn(self._text if text is None else text, self._name, self._base_dir, *args)
        except InputError as e:
            if modified:
                raise InputError(re.sub(re.escape(self._name) + r":\d+: ", self._name + ": ", str(e))) from None
            raise

    _modified = False  # the document was changed from Python (its text is regenerated)

    def _replace(self, doc):
        text = _floesim.dict_to_toml(doc)
        resolved = self._call(_floesim.check_config, text=text)
        # Read back from the text: tuples, NumPy arrays and scalars become plain lists and numbers.
        doc = _floesim.toml_to_dict(text, self._name)
        self._doc, self._text, self._resolved, self._resolved_doc = doc, text, resolved, None
        self._modified = True

    def _set(self, path, value):
        doc = copy.deepcopy(self._doc)
        node = doc
        for key in path[:-1]:
            node = node[key] if isinstance(key, int) else node.setdefault(key, {})
        node[path[-1]] = copy.deepcopy(value)
        self._replace(doc)

    def _delete(self, path):
        doc = copy.deepcopy(self._doc)
        node = doc
        try:
            for key in path[:-1]:
                node = node[key]
            del node[path[-1]]
        except (KeyError, IndexError):
            raise KeyError(_qualified(path)) from None
        self._replace(doc)

    def _lookup(self, path):
        """(value, True) from the document, else (value, False) from the resolved configuration."""
        for source, from_doc in ((self._doc, True), (self._resolved_dict(), False)):
            node = source
            try:
                for key in path:
                    node = node[key]
                return node, from_doc
            except (KeyError, IndexError, TypeError):
                continue
        raise KeyError(f"{_qualified(path)}: not a key of this configuration")


def _qualified(path):
    out = ""
    for key in path:
        out += f"[{key}]" if isinstance(key, int) else (("." if out else "") + key)
    return out


class _Table:
    """A view of one table of a Config; writes go through Config checks."""

    def __init__(self, config, path):
        self._config, self._path = config, path

    def __getitem__(self, key):
        value, _ = self._config._lookup(self._path + (key,))
        path = self._path + (key,)
        if isinstance(value, dict):
            return _Table(self._config, path)
        if _is_table_array(value):
            return _TableArray(self._config, path)
        return _frozen(copy.deepcopy(value))

    def __setitem__(self, key, value):
        self._config._set(self._path + (key,), value)

    def __delitem__(self, key):
        """Removes a key from the document: it goes back to its default."""
        self._config._delete(self._path + (key,))

    def keys(self):
        out = []
        for source in (self._config._doc, self._config._resolved_dict()):
            try:
                node = source
                for key in self._path:
                    node = node[key]
            except (KeyError, IndexError, TypeError):
                continue
            out += [k for k in node if k not in out]
        return out

    def __iter__(self):
        return iter(self.keys())

    def __contains__(self, key):
        return key in self.keys()

    def items(self):
        return [(k, self[k]) for k in self.keys()]

    def to_dict(self):
        """The values in force in this table, as plain nested dicts and lists."""
        out = {}
        for k in self.keys():
            v = self[k]
            out[k] = v.to_dict() if isinstance(v, (_Table, _TableArray)) else v
        return out

    def __repr__(self):
        return f"<floesim.Config table [{_qualified(self._path)}] {self.to_dict()!r}>"


class _TableArray:
    """A view of an array of tables ([[floes.floe]], [[fracture.load]])."""

    def __init__(self, config, path):
        self._config, self._path = config, path

    def _list(self):
        return self._config._lookup(self._path)[0]

    def __len__(self):
        return len(self._list())

    def __getitem__(self, i):
        n = len(self)
        if not -n <= i < n:
            raise IndexError(f"{_qualified(self._path)}: index {i} out of range ({n} tables)")
        return _Table(self._config, self._path + (i % n,))

    def __setitem__(self, i, table):
        self._config._set(self._path + (i % len(self),), table)

    def __delitem__(self, i):
        self._config._delete(self._path + (i % len(self),))

    def __iter__(self):
        return (self[i] for i in range(len(self)))

    def append(self, table):
        self._config._set(self._path, copy.deepcopy(self._list()) + [table])

    def to_dict(self):
        return [t.to_dict() for t in self]

    def __repr__(self):
        return f"<floesim.Config tables [[{_qualified(self._path)}]], {len(self)}>"


class Simulation(_floesim.Simulation):
    """A simulation built from a Config (or a configuration file's path).

    step(t_stop=None) takes one step (at most dt_max) and returns dt;
    run_until(t) advances to t landing on every output time on the way, as
    `floesim run --until t` does, so states at those times equal its records;
    run(output, until=-1) runs to [run] t_end (or until) writing a run file.
    state is an (n, 12) array (columns STATE_COLUMNS), polygons() the world
    outlines, energies() and lcp() dicts, sea_elevation() the sea on its grid.
    """

    def __init__(self, config):
        if not isinstance(config, Config):
            config = Config.load(config)
        self.config = config.copy()
        config._call(super().__init__)

    @classmethod
    def from_run(cls, path):
        """The simulation at the checkpoint of the run file `path` (docs/formats.md,
        "Checkpoint and restart"), with the run's own configuration: stepping it
        on (step, run_until) gives the states the run would have had, bit for
        bit. Raises InputError if the file has no checkpoint."""
        path = os.fspath(path)
        info = _floesim.read_run_info(path)
        config = Config(info["config"], name=path + ": config attribute",
                        base_dir=os.path.dirname(os.path.abspath(path)))
        sim = cls(config)
        sim._restore(path)
        return sim

    def run(self, output, until=-1.0):
        """Runs to [run] t_end (or until) from the present state, writing the run
        file `output` (and its .xmf); returns a summary dict."""
        return super().run(os.fspath(output), until)

    def sea_coordinates(self):
        """(x, y): the sea grid's cell centres (m); y is empty for a 1D sea."""
        g = self.sea_grid()
        (nx, ny), (lx, ly) = g["cells"], g["size"]
        if g["dims"] == 0:
            return np.zeros(0), np.zeros(0)
        x = (np.arange(nx) + 0.5) * lx / nx
        y = (np.arange(ny) + 0.5) * ly / ny if g["dims"] == 2 else np.zeros(0)
        return x, y

    def __repr__(self):
        return f"<floesim.Simulation {self.config.name!r} t={self.time:g} s, {self.floe_count} floes>"


class RunFile:
    """A run file (docs/formats.md) read without h5py. Datasets load on first use.

    time [T]; state [T, n, 12] (STATE_COLUMNS); energy [T, k] with
    energy_columns; lcp [T, 4] (LCP_COLUMNS); eta [T, ny, nx] or [T, nx] with
    sea_x, sea_y; info (status, config, records, datasets); run[path] reads any
    dataset, e.g. run["/floes/mass"].
    """

    def __init__(self, path):
        self.path = os.fspath(path)
        self.info = _floesim.read_run_info(self.path)
        self._cache = {}

    def _read(self, dataset):
        if dataset not in self._cache:
            self._cache[dataset] = _floesim.read_dataset(self.path, dataset)
        return self._cache[dataset]

    def __getitem__(self, dataset):
        return self._read(dataset if dataset.startswith("/") else "/" + dataset)[0]

    def columns(self, dataset):
        return list(self._read(dataset if dataset.startswith("/") else "/" + dataset)[1])

    @property
    def datasets(self):
        return dict(self.info["datasets"])

    @property
    def status(self):
        return self.info["status"]

    @property
    def config(self):
        """The resolved configuration the run was made with, as a Config."""
        return Config(self.info["config"], name=f"{self.path} (config attribute)")

    @property
    def time(self):
        return self["/time"]

    @property
    def state(self):
        return self["/floes/state"]

    @property
    def energy(self):
        return self["/diagnostics/energy"]

    @property
    def energy_columns(self):
        return list(self.info["energy_columns"])

    def energies(self):
        """{column: [T] array} for every energy column (the last is "total")."""
        e = self.energy
        return {name: e[:, k] for k, name in enumerate(self.energy_columns)}

    @property
    def lcp(self):
        return self["/diagnostics/lcp"]

    @property
    def has_sea(self):
        return "/sea/eta" in self.info["datasets"]

    @property
    def eta(self):
        return self["/sea/eta"]

    @property
    def sea_x(self):
        return self["/sea/x"]

    @property
    def sea_y(self):
        return self["/sea/y"]

    @property
    def fracture_events(self):
        """[k, 17] fracture initiations (FRACTURE_EVENT_COLUMNS); empty without fracture."""
        if "/events/fracture" not in self.info["datasets"]:
            return np.zeros((0, len(FRACTURE_EVENT_COLUMNS)))
        return self["/events/fracture"]

    @property
    def collision_events(self):
        """[k, 7] collisions (COLLISION_EVENT_COLUMNS; [run] record_collisions): one row per
        solve and pair of floes; empty when not recorded."""
        if "/events/collisions" not in self.info["datasets"]:
            return np.zeros((0, len(COLLISION_EVENT_COLUMNS)))
        return self["/events/collisions"]

    @property
    def mass(self):
        return self["/floes/mass"]

    @property
    def thickness(self):
        return self["/floes/thickness"]

    @property
    def is_static(self):
        return self["/floes/static"] != 0

    def polygons(self, record=-1):
        """World outlines of the floes at one record, as (k, 2) arrays indexed by
        floe number; None for a floe that does not exist then (split, or not yet made)."""
        offsets = self["/floes/offsets"].astype(int)
        body = self["/floes/vertices"]
        state = self.state[record]
        out = []
        for i in range(len(offsets) - 1):
            x, y, yaw = state[i, 0], state[i, 1], state[i, 2]
            if np.isnan(x):
                out.append(None)
                continue
            c, s = np.cos(yaw), np.sin(yaw)
            p = body[offsets[i]:offsets[i + 1]]
            out.append(np.column_stack((x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1])))
        return out

    def __repr__(self):
        return f"<floesim.RunFile {self.path!r}: {self.info['records']} records, {self.info['floes']} floes>"


def read_run(path):
    """Opens a run file: see RunFile."""
    return RunFile(path)


def compare_runs(a, b, rtol=1e-6, atol=1e-9):
    """Compares run file a with the reference b as `floesim compare` does; returns
    {"equal", "datasets_compared", "differences": [{dataset, what, count, max_abs, at}]}."""
    return _floesim.compare_runs(os.fspath(a), os.fspath(b), rtol, atol)


InputError.__module__ = RunError.__module__ = __name__
