// Eigen's large products go through the system's BLAS (cmake/eigen_blas.cmake),
// and the calibration calls them from two threads at once: the diagnosis on
// its own thread while the main one computes the uncertainty maps and draws
// the figures (app/pipeline.cc). A BLAS built without locks for such callers
// (OpenBLAS's single-threaded build without USE_LOCKING) shares its work
// buffers between them and returns wrong products now and then; this test
// fails on such a system instead of a calibration going quietly wrong.
#include <dlfcn.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace rtscalib {
namespace {

TEST(EigenBlas, ProductsFromFourThreadsAtOnceEqualTheSerialOnes) {
#ifndef EIGEN_USE_BLAS
  GTEST_SKIP() << "built without EIGEN_USE_BLAS";
#endif
  // Sizes of the diagnosis's projections (many rows, a few hundred columns)
  // scaled down, large enough for the BLAS's blocked kernels and buffers.
  constexpr int kMatrices = 6, kThreads = 4, kRounds = 40;
  std::vector<Eigen::MatrixXd> q, x, expected;
  for (int i = 0; i < kMatrices; ++i) {
    q.push_back(Eigen::MatrixXd::Random(4000 + 500 * i, 40));
    x.push_back(Eigen::MatrixXd::Random(q.back().rows(), 60));
    expected.push_back(q.back().transpose() * x.back());
  }
  std::atomic<int> wrong{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int round = 0; round < kRounds; ++round) {
        const int i = (round + t) % kMatrices;
        const Eigen::MatrixXd c = q[i].transpose() * x[i];
        // The same kernels on the same data: equal to the last bit.
        if (c != expected[i]) ++wrong;
      }
    });
  }
  for (std::thread& th : threads) th.join();
  EXPECT_EQ(wrong.load(), 0) << "of " << kThreads * kRounds
                             << " concurrent products; the system's libblas.so.3 is not "
                                "safe to call from several threads";
}

// cmake/blas_threads.cc, compiled into every executable, asks OpenBLAS for
// one thread per call and ends its worker threads: the calibration's own
// threads and CI's two test processes keep the cores busy, and a second
// BLAS thread would spin against them.
TEST(EigenBlas, OpenBlasRunsEachCallOnItsCallersThread) {
  using GetThreads = int (*)();
  const auto get = reinterpret_cast<GetThreads>(::dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  if (get == nullptr) GTEST_SKIP() << "the system's BLAS is not OpenBLAS";
  if (std::getenv("OPENBLAS_NUM_THREADS") != nullptr) {
    // ctest starts every test with OPENBLAS_NUM_THREADS=1 (CMakeLists.txt),
    // which alone gives one thread: the executable's own request is checked
    // in this test run again without the variable, as a user starts it.
    const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe");
    const std::string command = "env -u OPENBLAS_NUM_THREADS '" + self.string() +
                                "' --gtest_filter=EigenBlas.OpenBlasRunsEachCallOnItsCallersThread"
                                " > /dev/null";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    return;
  }
  EXPECT_EQ(get(), 1);
  // And its worker threads, started when it was loaded, are ended (they
  // would spin for a tenth of a second at every program's start): this
  // process runs on its main thread alone.
  size_t tasks = 0;
  for (const auto& t : std::filesystem::directory_iterator("/proc/self/task")) {
    (void)t;
    ++tasks;
  }
  EXPECT_EQ(tasks, 1u);
}

}  // namespace
}  // namespace rtscalib
