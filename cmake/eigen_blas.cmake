# Eigen's large double-precision products through the system's BLAS
# (EIGEN_USE_BLAS). The diagnosis projects a few hundred candidate columns
# through the fit's Jacobian (tens of thousands of rows), and the refinement
# and the uncertainty maps multiply matrices of that size: Debian's OpenBLAS
# (libopenblas0-pthread, scripts/install-deps.sh) picks AVX2/AVX-512 kernels
# at run time where Eigen, built for the x86-64 baseline, has SSE2 only, and
# in the sanitized build its kernels are not instrumented where Eigen's are
# (diagnose_benchmark and the one-board test: docs/testing.md).
#
# The generic libblas.so (BLA_VENDOR Generic) is linked, not a vendor's
# library: at run time libblas.so.3 is whichever BLAS Debian's alternatives
# name, OpenBLAS once installed, the reference or ATLAS otherwise (slower,
# the same results up to rounding). Ceres and SuiteSparse load the same one.
#
# The BLAS goes first on every executable's link line, kept where
# --as-needed would drop it: Debian's Ceres links ATLAS's libf77blas too,
# and the first library in an executable's list that defines dgemm_ serves
# the whole process (ATLAS's is no faster than Eigen's own).
#
# Included by the project (every target links rtscalib::eigen_blas) and by
# the installed package's config: every translation unit that instantiates
# Eigen's products, the consumer's too, must agree on EIGEN_USE_BLAS, and
# the static libraries need the BLAS.
set(BLA_VENDOR Generic)
find_package(BLAS REQUIRED)
if(NOT TARGET rtscalib::eigen_blas)
  list(JOIN BLAS_LIBRARIES "," rtscalib_blas_files)
  add_library(rtscalib::eigen_blas INTERFACE IMPORTED)
  set_target_properties(rtscalib::eigen_blas PROPERTIES
    INTERFACE_COMPILE_DEFINITIONS EIGEN_USE_BLAS
    INTERFACE_LINK_LIBRARIES BLAS::BLAS
    INTERFACE_LINK_OPTIONS "LINKER:--push-state,--no-as-needed,${rtscalib_blas_files},--pop-state"
    # Every executable asks OpenBLAS for one thread per call (blas_threads.cc).
    INTERFACE_SOURCES
      "$<$<STREQUAL:$<TARGET_PROPERTY:TYPE>,EXECUTABLE>:${CMAKE_CURRENT_LIST_DIR}/blas_threads.cc>")
endif()
