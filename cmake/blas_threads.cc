// Compiled into every executable that links rtscalib (cmake/eigen_blas.cmake).
//
// One BLAS thread per caller. The calibration runs its own threads (the
// diagnosis beside the figures, Ceres's evaluations, the detection jobs),
// and CI runs two test processes side by side: a threaded BLAS splitting
// each product over every core would spin its workers against them.
// Debian's threaded OpenBLAS (libopenblas0-pthread) is the one that is safe
// to call from several threads at once (its single-threaded build is not:
// tests/geometry/eigen_blas_test.cc); this asks it for one thread per call.
// Other BLAS libraries do not have the function and are left as they are.
#include <dlfcn.h>

namespace {

struct RtscalibOneBlasThread {
  RtscalibOneBlasThread() {
    using SetThreads = void (*)(int);
    if (auto set = reinterpret_cast<SetThreads>(::dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) {
      set(1);
      // OpenBLAS started its worker threads when it was loaded, before this
      // runs, and each spins for about a tenth of a second (sched_yield in
      // a loop) before it sleeps: at a program's start, beside the work
      // that has begun. With one thread per call they are never used:
      // they are ended now (OpenBLAS starts them again if a later call
      // asks for more threads).
      using Shutdown = int (*)();
      if (auto end = reinterpret_cast<Shutdown>(::dlsym(RTLD_DEFAULT, "blas_thread_shutdown_"))) {
        end();
      }
    }
  }
};
const RtscalibOneBlasThread rtscalib_one_blas_thread;

}  // namespace
