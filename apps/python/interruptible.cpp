#include <chrono>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>

#include "apps/python/bindings.h"
#include "core/interrupt.h"

namespace uavsim::python {

void RunInterruptibly(const std::function<void()>& work) {
  core::ClearInterrupt();
  std::mutex mu;
  std::condition_variable cv;
  bool done = false;
  std::exception_ptr error;
  std::optional<py::error_already_set> signalled;  // what Python's handler raised
  {
    py::gil_scoped_release release;
    std::thread worker([&] {
      try {
        work();
      } catch (...) {
        error = std::current_exception();
      }
      const std::lock_guard<std::mutex> lock(mu);
      done = true;
      cv.notify_all();
    });
    std::unique_lock<std::mutex> lock(mu);
    while (!cv.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; })) {
      if (signalled) continue;
      lock.unlock();
      {
        py::gil_scoped_acquire gil;
        if (PyErr_CheckSignals() != 0) {
          signalled.emplace();
          core::RequestInterrupt();
        }
      }
      lock.lock();
    }
    lock.unlock();
    worker.join();
  }
  core::ClearInterrupt();
  if (signalled) throw *signalled;
  if (error) std::rethrow_exception(error);
}

}  // namespace uavsim::python
