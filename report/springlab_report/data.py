"""Reading what springlab writes: experiment settings (<name>.json), their
tidy CSV tables, and the integrator table (integrators.json).

The schema is the program's: a settings file names its tables and their
columns ("tables": [{"file", "suffix", "columns"}]); this module checks each
file's header against that list and hands the columns out as text or as
numbers when a figure asks for them, so a malformed value is reported with
its file, line and column only where it is used. A kind module names the
columns it reads (Table.require), never the whole schema.
"""

import csv
import json
import math

import numpy as np


class DataError(Exception):
    """A malformed input file: the message names the file and, if known, the line."""

    def __init__(self, path, line, message):
        where = str(path) if line is None else "%s:%d" % (path, line)
        super().__init__("%s: %s" % (where, message))


STATUSES = ("completed", "diverged", "failed")


def read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as exc:
        raise DataError(path, None, "cannot read (%s)" % exc.strerror) from None
    except UnicodeDecodeError:
        raise DataError(path, None, "not UTF-8 text") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise DataError(path, exc.lineno, "malformed JSON: %s (column %d)" % (exc.msg, exc.colno)) \
            from None


class Table:
    """One CSV table: its header and rows as text; columns converted on demand."""

    def __init__(self, path, header, rows, lines):
        self.path = path
        self.header = header
        self._rows = rows        # list of lists of str
        self._lines = lines      # the file line of each row, for messages
        self._index = {h: j for j, h in enumerate(header)}
        self._cache = {}

    def __len__(self):
        return len(self._rows)

    def has(self, column):
        return column in self._index

    def require(self, *columns):
        missing = [c for c in columns if c not in self._index]
        if missing:
            raise DataError(self.path, 1, "missing column%s %s (header: %s)" % (
                "s" if len(missing) > 1 else "", ", ".join("'%s'" % m for m in missing),
                ",".join(self.header)))
        return self

    def text(self, column):
        """The column as a list of strings."""
        key = ("text", column)
        if key not in self._cache:
            j = self._index[column]
            self._cache[key] = [row[j] for row in self._rows]
        return self._cache[key]

    def num(self, column):
        """The column as floats; an empty field is NaN."""
        key = ("num", column)
        if key not in self._cache:
            j = self._index[column]
            out = np.empty(len(self._rows))
            for r, row in enumerate(self._rows):
                field = row[j]
                if field == "":
                    out[r] = math.nan
                    continue
                try:
                    out[r] = float(field)
                except ValueError:
                    raise DataError(self.path, self._lines[r], "column '%s': '%s' is not a number"
                                    % (column, field)) from None
            self._cache[key] = out
        return self._cache[key]

    def status(self, column="status"):
        """A status column (completed, diverged, failed), checked."""
        values = self.text(column)
        for r, v in enumerate(values):
            if v not in STATUSES:
                raise DataError(self.path, self._lines[r], "column '%s': '%s' is not one of %s"
                                % (column, v, ", ".join(STATUSES)))
        return values

    def groups(self, *columns):
        """Row indices grouped by the text of the named columns, in order of
        first appearance."""
        out = {}
        cols = [self.text(c) for c in columns]
        for r in range(len(self._rows)):
            out.setdefault(tuple(c[r] for c in cols), []).append(r)
        return {k: np.asarray(v, dtype=int) for k, v in out.items()}

    def row(self, r):
        return {h: self._rows[r][j] for h, j in self._index.items()}


def read_table(path, columns=None):
    """A CSV table; with `columns` (the settings file's list) the header must
    be exactly that."""
    try:
        with open(path, newline="", encoding="utf-8-sig") as f:
            reader = csv.reader(f, strict=True)
            try:
                header = [h.strip() for h in next(reader)]
            except StopIteration:
                raise DataError(path, 1, "file is empty (expected a header line)") from None
            if len(set(header)) != len(header):
                raise DataError(path, 1, "a column appears twice in the header")
            if columns is not None and header != list(columns):
                raise DataError(path, 1, "header is %s, but the settings file says %s"
                                % (",".join(header), ",".join(columns)))
            rows, lines = [], []
            for row in reader:
                if not row or (len(row) == 1 and not row[0].strip()):
                    continue
                if len(row) != len(header):
                    raise DataError(path, reader.line_num, "%d fields, but the header has %d "
                                    "columns" % (len(row), len(header)))
                rows.append([field.strip() for field in row])
                lines.append(reader.line_num)
    except OSError as exc:
        raise DataError(path, None, "cannot read (%s)" % exc.strerror) from None
    except UnicodeDecodeError:
        raise DataError(path, None, "not UTF-8 text") from None
    except csv.Error as exc:
        raise DataError(path, None, "malformed CSV (%s)" % exc) from None
    return Table(path, header, rows, lines)


class Experiment:
    """One experiment's settings and tables, as found in the data directory."""

    def __init__(self, kind, name, settings, settings_path):
        self.kind = kind
        self.name = name
        self.settings = settings or {}
        self.settings_path = settings_path
        self.tables = {}   # suffix ("" for <name>.csv, "runs", ...) -> Table
        self.notes = []    # what is missing, for the page

    def table(self, suffix=""):
        return self.tables.get(suffix)

    def title(self):
        t = self.settings.get("title")
        return t if isinstance(t, str) and t else self.name

    def setting(self, key, default=None):
        return self.settings.get(key, default)


def _tables_of(settings, name, data_dir):
    """[(suffix, file, columns or None)]: from the settings file, or, for data
    written before settings files listed their tables, <name>.csv and
    <name>-<suffix>.csv as found."""
    declared = settings.get("tables")
    if isinstance(declared, list):
        out = []
        for t in declared:
            if isinstance(t, dict) and isinstance(t.get("file"), str) \
                    and isinstance(t.get("columns"), list):
                out.append((str(t.get("suffix", "")), t["file"], [str(c) for c in t["columns"]]))
        return out
    out = [("", name + ".csv", None)] if (data_dir / (name + ".csv")).is_file() else []
    for p in sorted(data_dir.glob(name + "-*.csv")):
        suffix = p.stem[len(name) + 1:]
        if ".shard-" not in suffix:
            out.append((suffix, p.name, None))
    return out


def load_experiments(data_dir, known_kinds):
    """Every experiment settings file in the directory whose kind the report
    knows, with its tables; plus notes for the page."""
    notes = []
    experiments = []
    for p in sorted(q for q in data_dir.glob("*.json") if q.is_file()):
        if p.name == "integrators.json" or ".shard-" in p.name:
            continue
        settings = read_json(p)
        if is_bench_doc(settings):
            continue
        kind = settings.get("experiment") if isinstance(settings, dict) else None
        if not isinstance(kind, str):
            notes.append("%s is not an experiment settings file (no \"experiment\" key): ignored."
                         % p.name)
            continue
        if kind not in known_kinds:
            notes.append("%s: experiment kind '%s' is not known to this report: ignored."
                         % (p.name, kind))
            continue
        e = Experiment(kind, p.stem, settings, p)
        if settings.get("complete") is False:
            e.notes.append("%s says the run is incomplete (%s of %s tasks): the tables hold only "
                           "the finished tasks." % (p.name, settings.get("tasks_done"),
                                                    settings.get("tasks_total")))
        for suffix, file, columns in _tables_of(settings, p.stem, data_dir):
            path = data_dir / file
            if not path.is_file():
                shards = sorted(data_dir.glob(path.stem + ".shard-*-of-*.csv"))
                e.notes.append("%s is missing%s." % (file, ", but %d shard file(s) are there: merge "
                                                     "them with `springlab experiment ... --merge "
                                                     "N`" % len(shards) if shards else ""))
                continue
            t = read_table(path, columns)
            if len(t) == 0:
                e.notes.append("%s has a header but no rows." % file)
            else:
                e.tables[suffix] = t
        experiments.append(e)
    return experiments, notes


def is_bench_doc(doc):
    """A Google Benchmark JSON file (not an experiment's settings)."""
    return isinstance(doc, dict) and isinstance(doc.get("benchmarks"), list) \
        and isinstance(doc.get("context"), dict)


def finite(x):
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


class Columns:
    """Named columns of a table for array code: numbers as float arrays,
    the rest as lists of text, chosen by the kind module."""

    def __init__(self, table, numbers=(), texts=()):
        table.require(*numbers, *texts)
        self.table = table
        self.n = len(table)
        self._cols = {c: table.num(c) for c in numbers}
        self._cols.update({c: table.text(c) for c in texts})

    def __len__(self):
        return self.n

    def __getitem__(self, name):
        return self._cols[name]

    def groups(self, *names):
        return self.table.groups(*names)

    def row(self, r):
        return {name: (col[r] if isinstance(col, list) else float(col[r]))
                for name, col in self._cols.items()}
