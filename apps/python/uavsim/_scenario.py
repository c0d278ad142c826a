"""Scenarios from a file or a dict, with --set overrides (JSON pointers)."""
import copy
import json
import os

from . import _uavsim
from ._errors import ScenarioError


class Scenario:
    """A scenario: a file (or a dict) and the overrides set on it.

    Relative paths inside a file resolve against its folder; inside a dict,
    and in overrides, against the working directory (as `--set` does).
    """

    def __init__(self, source, overrides=()):
        if isinstance(source, Scenario):
            self.path, self.document = source.path, source.document
            self._overrides = list(source._overrides)
        elif isinstance(source, (str, os.PathLike)):
            self.path, self.document = os.fspath(source), None
            self._overrides = []
        elif isinstance(source, dict):
            self.path, self.document = None, copy.deepcopy(source)
            self._overrides = []
        else:
            raise TypeError("a scenario is a file path, a dict or a Scenario, got %r" % type(source))
        for pointer, value in overrides:
            self.set(pointer, value)

    @property
    def file(self):
        """The name errors give: the path, or "<dict>"."""
        return self.path if self.path is not None else "<dict>"

    def set(self, pointer, value):
        """Sets the value at a JSON pointer, as `--set POINTER=VALUE` does; returns self."""
        # As the command line refuses it (exit 2); text that is not UTF-8 (a
        # lone surrogate) would not reach the engine.
        if not isinstance(pointer, str) or not pointer.startswith("/") or not _is_utf8(pointer):
            message = "--set %r: expected a JSON pointer (UTF-8 text starting with /)" % (pointer,)
            raise ScenarioError("%s: %s" % (self.file, message), self.file, "", message)
        self._overrides.append(pointer + "=" + json.dumps(value))
        return self

    def copy(self):
        return Scenario(self)

    def overrides(self):
        """The overrides as `--set` arguments, in the order set."""
        return list(self._overrides)

    def _args(self, extra=()):
        document = "" if self.document is None else json.dumps(self.document)
        return self.path or "", document, self._overrides + list(extra)

    def resolved(self):
        """The scenario with every default filled (`uavsim validate --resolved`), as a dict."""
        return json.loads(_uavsim.resolved(*self._args()))

    def validate(self, methods=()):
        """Checks every rule `uavsim validate` checks; raises ScenarioError."""
        from ._method import split_methods
        names, hosted = split_methods(methods)
        extra = ["/pipeline/methods=" + json.dumps(names)] if names else []
        _uavsim.validate(*self._args(extra), list(hosted))
        return self

    def __repr__(self):
        return "Scenario(%r%s)" % (self.path if self.path else "<dict>",
                                   ", %d overrides" % len(self._overrides) if self._overrides else "")


def _is_utf8(text):
    try:
        text.encode("utf-8")
        return True
    except UnicodeEncodeError:
        return False


def load(source):
    """A Scenario from a file path or a dict (validated: raises ScenarioError)."""
    scenario = Scenario(source)
    scenario.validate()
    return scenario


def validate(source, methods=()):
    """Raises ScenarioError (file, pointer, message) where `uavsim validate` exits with 2."""
    Scenario(source).validate(methods)
