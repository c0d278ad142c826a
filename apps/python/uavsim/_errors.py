"""The error a scenario or a command's usage raises (exit code 2 on the command line)."""


class ScenarioError(ValueError):
    """Bad input: the command line's one line, with its parts.

    file     the scenario (or spec) file the error is about, "<dict>" for a
             scenario given as a dict, None for a usage error (a bad option)
    pointer  the JSON pointer of the offending value ("" for the document
             itself), None for a usage error
    message  what is wrong there
    str(e) is the line `uavsim` prints before exiting with code 2.
    """

    def __init__(self, line, file=None, pointer=None, message=None):
        super().__init__(line)
        self.file = file
        self.pointer = pointer
        self.message = message if message is not None else line


ScenarioError.__module__ = "uavsim"  # shown as uavsim.ScenarioError in tracebacks
