#include <pthread.h>

#include <atomic>
#include <mutex>

#include "apps/python/bindings.h"

namespace uavsim::python {
namespace {

std::atomic<int> active{0};
thread_local bool forking = false;
thread_local PyGILState_STATE gil_state;

void Prepare() {
  if (active.load() == 0) return;
  forking = true;
  gil_state = PyGILState_Ensure();
  PyOS_BeforeFork();
}

void Parent() {
  if (!forking) return;
  forking = false;
  PyOS_AfterFork_Parent();
  PyGILState_Release(gil_state);
}

void Child() {
  if (!forking) return;
  forking = false;
  PyOS_AfterFork_Child();  // this thread is the child's only one and holds the GIL
  PyEval_SaveThread();     // its thread state kept: PyGILState_Ensure finds it again
}

}  // namespace

ForkSafety::ForkSafety(bool on) : on_(on) {
  static std::once_flag registered;
  std::call_once(registered, [] { pthread_atfork(Prepare, Parent, Child); });
  if (on_) ++active;
}

ForkSafety::~ForkSafety() {
  if (on_) --active;
}

}  // namespace uavsim::python
