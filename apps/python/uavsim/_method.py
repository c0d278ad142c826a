"""uavsim.PythonMethod: a Python function as a localization method in the loop."""
import re


class PythonMethod:
    """A method the run calls at each window's deadline (pipeline/edge/scripted_edge.h's contract).

    fn(latents, offsets_s, mask) -> position or None
      latents    float32 [L, 3, F, z]: window l (0 oldest, L - 1 the window
                 being estimated), modality m (0 camera, 1 LiDAR, 2 radar),
                 frame f in capture order, the node's IB-CC latent
      offsets_s  float32 [L, 3, F]: capture time minus the window's start (s)
      mask       float32 [L, 3, F]: 1 for a frame, 0 for padding
      returns    3 finite numbers (world ENU metres, the target at the
                 window's end) or None (no estimate this window); one more
                 than 1 km outside the scenario's bounds counts as no
                 estimate (metrics.json's rejected_estimates). Anything else
                 stops the run: TypeError (not 3 numbers) or ValueError (not
                 finite), naming the method and the window.
    L is history_windows. With window_time=True (our addition to the
    TorchScript contract) it is called fn(latents, offsets_s, mask, t_end_s),
    t_end_s the window's end (s of simulated time). The function is not called before the first
    window that holds a frame. It runs on the nodes' latents, so the
    scenario's model (/pipeline/model) must exist. An exception it raises
    stops the run (nothing is written) and reaches the caller as it is.
    """

    def __init__(self, name, fn, history_windows=1, window_time=False):
        if not isinstance(name, str) or not re.fullmatch(r"[A-Za-z0-9_]{1,64}", name):
            raise ValueError("a method's name is letters, digits and _ (at most 64), got %r" % (name,))
        if not callable(fn):
            raise TypeError("PythonMethod(%r, fn): fn must be callable" % name)
        if not isinstance(history_windows, int) or not 1 <= history_windows <= 10000:
            raise ValueError("history_windows is an integer from 1 to 10000")
        self.name, self.fn, self.history_windows = name, fn, history_windows
        self.window_time = bool(window_time)

    def entry(self):
        """Its /pipeline/methods entry."""
        return {"type": "python", "name": self.name, "history_windows": self.history_windows}

    def __repr__(self):
        return "PythonMethod(%r, history_windows=%d)" % (self.name, self.history_windows)


def split_methods(methods):
    """(the /pipeline/methods list, {name: (fn, window_time)} of the Python ones)."""
    if methods is None:
        return [], {}
    if isinstance(methods, (str, PythonMethod)):
        methods = [methods]
    entries, hosted = [], {}
    for m in methods:
        if isinstance(m, PythonMethod):
            entries.append(m.entry())
            hosted[m.name] = (m.fn, m.window_time)
        elif isinstance(m, (str, dict)):
            entries.append(m)
        else:
            raise TypeError("a method is a name, a TorchScript entry (dict) or a PythonMethod, got %r" % (m,))
    return entries, hosted
