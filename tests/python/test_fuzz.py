"""Fuzz from Python (issue 69): Scenario.set/validate/resolved on random
pointers and values, and a PythonMethod's random return values. Seeded.

UAVSIM_FUZZ_ITERATIONS (default 500) is the number of set/validate/resolved
rounds; the method's return values are a fifth as many. A long fuzz by hand:
  UAVSIM_FUZZ_ITERATIONS=20000 UAVSIM_FUZZ_SEED=7 PYTHONPATH=build/python \\
    UAVSIM_BUILD_DIR=build /usr/bin/python3 -m pytest -q tests/python/test_fuzz.py
"""
import os
import random
import re

import numpy as np
import pytest
import uavsim
from conftest import DEFAULT

ITERATIONS = int(os.environ.get("UAVSIM_FUZZ_ITERATIONS", "500"))
SEED = int(os.environ.get("UAVSIM_FUZZ_SEED", "69"))


# --- Scenario.set(pointer, value), then .validate() and .resolved() ---------

def escape(key):
    return key.replace("~", "~0").replace("/", "~1")


def pointers(doc, at=""):
    """Every JSON pointer in doc: objects' keys and arrays' indices, nested."""
    if at:
        yield at
    if isinstance(doc, dict):
        for key, value in doc.items():
            yield from pointers(value, at + "/" + escape(key))
    elif isinstance(doc, list):
        for i, value in enumerate(doc):
            yield from pointers(value, at + "/%d" % i)


TEXT = ["", " ", "NaN", "nan", "Infinity", "-Infinity", "1e999", "-1e999", "0x10", "-0", "1e-400",
        "true", "null", "[]", "{}", "orbit", "grid", "fisheye_stereo", "ekf", "uavloc", "default",
        ".", "/", "..", "does/not/exist.json", "\u00e9t\u00e9", "\u6f22\u5b57", "\U0001f681",
        "a\x00b", "\t\n", "~0~1", "=", "/seed=3", "\u00e9" * 70, "x" * 5000, "\ud800"]
NUMBERS = [0, -0.0, 1, -1, 0.5, 2 ** 31, -2 ** 31 - 1, 2 ** 63, 2 ** 64, -2 ** 63 - 1, 10 ** 400,
           1e-308, 5e-324, 1e308, -1e308, 86400, 86400.0001, 1e9, float("nan"), float("inf"),
           float("-inf")]


def random_value(rng, like=None, depth=0):
    """A JSON-ish value: often one near `like` (the field's own value), else anything."""
    roll = rng.random()
    if like is not None and roll < 0.4:
        if isinstance(like, bool):
            return not like
        if isinstance(like, (int, float)):
            return rng.choice([like * rng.choice([-1, 0, 0.5, 2, 10, 1e6]), like + rng.randint(-3, 3),
                               rng.choice(NUMBERS), str(like)])
        if isinstance(like, str):
            return rng.choice([like + rng.choice(TEXT[:20]), like.upper(), like[: len(like) // 2]])
        if isinstance(like, list):
            copy = list(like)
            if copy and rng.random() < 0.5:
                copy.pop(rng.randrange(len(copy)))
            else:
                copy.append(random_value(rng, copy[0] if copy else None, depth + 1))
            return copy
        if isinstance(like, dict):
            copy = dict(like)
            if copy and rng.random() < 0.5:
                del copy[rng.choice(list(copy))]
            else:
                copy[rng.choice(TEXT)] = random_value(rng, depth=depth + 1)
            return copy
    kind = rng.randrange(9 if depth < 3 else 6)
    if kind == 0:
        return None
    if kind == 1:
        return rng.random() < 0.5
    if kind == 2:
        return rng.choice(NUMBERS)
    if kind == 3:
        return rng.uniform(-1, 1) * 10 ** rng.randint(-5, 12)
    if kind == 4:
        return rng.choice(TEXT)
    if kind == 5:
        return "".join(chr(rng.randint(1, 0x2FFF)) for _ in range(rng.randint(0, 12)))
    if kind == 6:
        return [rng.uniform(-100, 100) for _ in range(rng.choice([0, 1, 2, 3, 3, 4]))]
    if kind == 7:
        return [random_value(rng, depth=depth + 1) for _ in range(rng.randint(0, 4))]
    return {rng.choice(TEXT[:30]): random_value(rng, depth=depth + 1) for _ in range(rng.randint(0, 3))}


def random_pointer(rng, real):
    """A pointer of the scenario (most often) or one a little or very wrong."""
    p = rng.choice(real)
    if rng.random() < 0.5:
        return p
    return rng.choice([p + "/made_up", p.rsplit("/", 1)[0] + "/nope", p + "/-", p + "/99",
                       p + "/01", p + "/0", p + "/~2", p + "/", p + "//x", "/" + rng.choice(TEXT),
                       "/", "", "seed", p + "=x", p + "/\ud800"])


def shown(text, quote=False):
    """Text as an error's line shows it: on one line (control characters
    escaped), a pointer with a space or a colon quoted (core/error.cpp)."""
    out = ""
    for c in text:
        if c in "\n\r\t":
            out += {"\n": "\\n", "\r": "\\r", "\t": "\\t"}[c]
        elif ord(c) < 0x20 or ord(c) == 0x7f:
            out += "\\u%04x" % ord(c)
        else:
            out += "\\" + c if quote and c in '"\\' else c
    return '"%s"' % out if quote else out


def check_scenario_error(e, what):
    assert type(e) is uavsim.ScenarioError, "%s raised %s: %s" % (what, type(e).__name__, e)
    line = str(e)
    assert e.message and line.endswith(e.message), (what, line, e.message)
    if e.file is None:  # a usage error
        assert e.pointer is None and e.message == line, what
        return
    assert e.pointer is not None and line.startswith(shown(e.file) + ": "), (what, line)
    if e.pointer:
        quote = e.pointer == "/" or " " in e.pointer or ":" in e.pointer
        assert line.startswith(shown(e.file) + ": " + shown(e.pointer, quote) + ": "), (what, line)


def test_random_sets_validate_or_raise_a_scenario_error():
    rng = random.Random(SEED)
    resolved = uavsim.Scenario(DEFAULT).resolved()
    real = sorted(pointers(resolved))
    assert len(real) > 200 and "/pipeline/window_s" in real

    def value_at(p):
        node = resolved
        for token in p[1:].split("/"):
            token = token.replace("~1", "/").replace("~0", "~")
            node = node[int(token)] if isinstance(node, list) else node[token]
        return node

    counts = {"valid": 0, "ScenarioError": 0}
    for i in range(ITERATIONS):
        scenario = uavsim.Scenario(DEFAULT)
        sets = []
        for _ in range(rng.choice([1, 1, 1, 2, 3])):
            p = random_pointer(rng, real)
            value = random_value(rng, value_at(p) if p in real else None)
            sets.append((p, value))
        what = "round %d (seed %d): %r" % (i, SEED, sets)
        try:
            for p, value in sets:
                scenario.set(p, value)
            scenario.validate()
            assert isinstance(scenario.resolved(), dict), what
            counts["valid"] += 1
        except uavsim.ScenarioError as e:
            check_scenario_error(e, what)
            counts["ScenarioError"] += 1
        except Exception as e:  # noqa: BLE001: any other kind is the failure being looked for
            pytest.fail("%s raised %s: %s" % (what, type(e).__name__, e))
    print("set/validate/resolved rounds:", counts)
    assert counts["valid"] > 0 and counts["ScenarioError"] > 0


# --- a PythonMethod's return values --------------------------------------------

class Unprintable:
    def __repr__(self):
        raise RuntimeError("no repr")


class Surrogate:
    def __repr__(self):
        return "\ud800" * 3


class Long:
    def __repr__(self):
        return "L" * 10000


class ArrayLike:
    def __init__(self, values):
        self.values = values

    def __array__(self, dtype=None):
        return np.array(self.values, dtype=dtype)


class BrokenArray:
    def __array__(self, dtype=None):
        raise RuntimeError("cannot convert")


FLOATS = [np.float16, np.float32, np.float64, np.longdouble]
INTS = [np.int8, np.int16, np.int32, np.int64, np.uint8, np.uint16, np.uint32, np.uint64]


def random_return(rng):
    """(a return value, the error it must raise: None for a position or None)."""
    kind = rng.randrange(20)
    xyz = [rng.uniform(-200, 200) for _ in range(3)]
    if kind == 0:
        return None, None
    if kind == 1:  # 3 numbers in a list, a tuple, nested singletons
        value = rng.choice([list(xyz), tuple(xyz), [xyz], [[xyz]], [[x] for x in xyz],
                            [int(xyz[0]), xyz[1], np.float32(xyz[2])], range(3)])
        return value, None
    if kind in (2, 3):  # an array of 3 ints or floats in some shape
        dtype = rng.choice(FLOATS + INTS)
        shape = rng.choice([(3,), (1, 3), (3, 1), (1, 1, 3)])
        value = np.abs(np.array(xyz)).astype(dtype).reshape(shape)
        if rng.random() < 0.2:
            value = np.repeat(value, 2, axis=-1)[..., ::2]  # not contiguous
        return value, None
    if kind == 4:  # non-finite values
        bad = rng.choice([float("nan"), float("inf"), -float("inf")])
        xyz[rng.randrange(3)] = bad
        value = rng.choice([xyz, tuple(xyz), np.array(xyz, dtype=rng.choice(FLOATS))])
        return value, ValueError
    if kind == 5:  # a float16 that overflows
        with np.errstate(over="ignore"):
            return np.array([70000.0, 0, 0]).astype(np.float16), ValueError
    if kind == 6:  # text
        return rng.choice(["abc", "1 2 3", "123", "", "\u00e9\U0001f681", b"1.0", b"", bytearray(b"xyz"),
                           "x" * 1000]), TypeError
    if kind == 7:  # the wrong number of numbers
        n = rng.choice([0, 1, 2, 4, 5, 6, 9, 100])
        value = [rng.uniform(-9, 9) for _ in range(n)]
        return rng.choice([value, np.array(value), np.array(value).reshape(-1, 1),
                           rng.uniform(-9, 9), rng.randint(-9, 9), np.float64(1.0)]), TypeError
    if kind == 8:  # strings, None, bools, complex numbers among numbers
        odd = rng.choice(["1", None, {}, [], "x", 1j, object()])
        value = list(xyz)
        value[rng.randrange(3)] = odd
        return value, TypeError
    if kind == 9:  # arrays that do not hold numbers
        value = rng.choice([np.array(["1", "2", "3"]), np.array([b"1", b"2", b"3"]),
                            np.array([1 + 1j, 2, 3]), np.array([True, False, True]),
                            np.array([1, 2, 3], dtype=object), np.zeros(3, dtype="datetime64[s]"),
                            np.zeros(3, dtype="timedelta64[s]"), np.zeros(3, dtype="f8,f8"),
                            np.array([None, None, None])])
        return value, TypeError
    if kind == 10:  # ragged
        return rng.choice([[[1.0, 2.0], [3.0]], [1.0, [2.0, 3.0]], [[1.0], 2.0, 3.0],
                           [xyz, xyz[:2]]]), TypeError
    if kind == 11:  # containers that are not sequences of numbers
        return rng.choice([{"x": 1, "y": 2, "z": 3}, {1, 2, 3}, frozenset([1.0]), iter([1, 2, 3]),
                           (x for x in xyz), {1: 1.0, 2: 2.0, 3: 3.0}]), TypeError
    if kind == 12:  # objects
        return rng.choice([object(), Unprintable(), Surrogate(), Long(), BrokenArray(),
                           uavsim, print, Exception("x"), slice(1, 2, 3)]), TypeError
    if kind == 13:  # array-likes
        return ArrayLike(xyz), None
    if kind == 14:  # huge integers: beyond int64 they are objects to NumPy
        return [10 ** 30, 0, 0], TypeError
    if kind == 15:  # deep nesting
        value = xyz
        for _ in range(rng.randint(1, 30)):
            value = [value]
        return value, None
    if kind == 16:  # a masked array is its data; a 0-d array or a big one the wrong size
        return rng.choice([(np.ma.masked_array(xyz, mask=[0, 1, 0]), None), (np.array(1.0), TypeError),
                           (np.zeros((1000, 3)), TypeError)])
    if kind == 17:  # 3 numbers of bool type
        return rng.choice([[True, False, True], (True, True, True)]), TypeError
    if kind == 18:  # random nested junk
        return [rng.choice([1, "a", None, [1], {}, 2.5]) for _ in range(rng.randint(0, 5))], "any"
    return [np.float64(x) for x in xyz], None


def test_random_return_values_are_positions_or_name_the_method_and_window(tmp_path):
    rng = random.Random(SEED)
    values = [random_return(rng) for _ in range(max(ITERATIONS // 5, 20))]
    trace = str(tmp_path / "trace")
    duration = 3  # 15 windows of 0.2 s
    window_s = uavsim.Scenario(DEFAULT).resolved()["pipeline"]["window_s"]
    # Sense once; every run below replays the nodes' messages.
    uavsim.run(DEFAULT, duration=duration, quiet=True, trace=trace,
               methods=[uavsim.PythonMethod("fuzz", lambda *a: None)])
    done, runs, errors = 0, 0, 0
    while done < len(values):
        returned = []  # (index, window)

        def fn(latents, offsets_s, mask, t_end_s):
            i = done + len(returned)
            returned.append((i, round(t_end_s / window_s)))
            return values[i][0] if i < len(values) else None

        error = None
        runs += 1
        try:
            uavsim.run(DEFAULT, duration=duration, quiet=True, replay=trace,
                       methods=[uavsim.PythonMethod("fuzz", fn, window_time=True)])
        except Exception as e:  # noqa: BLE001: checked below
            error = e
        assert returned, "the method was never called"
        # Every value but the last returned was taken as a position or None.
        for i, _ in returned[:-1]:
            if i < len(values):
                assert values[i][1] in (None, "any"), "value %d, %r, was accepted" % (i, values[i][0])
        last, window = returned[-1]
        if last >= len(values):
            assert error is None, error
            break
        value, expected = values[last]
        if error is None:
            assert expected in (None, "any"), "value %d, %r, was accepted" % (last, value)
        else:
            message = str(error)
            assert expected == "any" or type(error) is expected, \
                "value %d, %r: %s: %s" % (last, value, type(error).__name__, message)
            assert type(error) in (TypeError, ValueError), message
            assert message.startswith('PythonMethod "fuzz" returned '), message
            assert type(value).__name__ in message.split(" at window ")[0], message
            assert re.search(r" at window %d: .*; expected 3 numbers \(x, y, z: world ENU metres\) "
                             r"or None$" % window, message), message
            assert len(message) < 250, message
            errors += 1
        done = last + 1
    print("method returns: %d values, %d runs, %d errors" % (len(values), runs, errors))
    assert errors > 0
