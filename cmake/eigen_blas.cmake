# Eigen's large double-precision products through the system's BLAS
# (EIGEN_USE_BLAS). The diagnosis projects a few hundred candidate columns
# through the fit's Jacobian (tens of thousands of rows), and the refinement
# and the uncertainty maps multiply matrices of that size: Debian's OpenBLAS
# (libopenblas0-pthread, scripts/install-deps.sh) picks AVX2/AVX-512 kernels
# at run time where Eigen, built for the x86-64 baseline, has SSE2 only.
# Measured on the 62,000 x 100 basis and 231 columns of the photo session:
# 42 GFLOP/s against Eigen's 17 in Release, and 44 against 3 in the
# sanitized build, where Eigen's own kernels are instrumented and the
# library is not (docs/testing.md).
#
# The generic libblas.so (BLA_VENDOR Generic) is linked, not a vendor's
# library: at run time libblas.so.3 is whichever BLAS Debian's alternatives
# name, OpenBLAS once installed, the reference or ATLAS otherwise (slower,
# the same results up to rounding). Ceres and SuiteSparse load the same one.
#
# Included by the project and by the installed package's config: every
# translation unit that instantiates Eigen's products, the consumer's too,
# must agree on EIGEN_USE_BLAS, and the static libraries need the BLAS.
set(BLA_VENDOR Generic)
find_package(BLAS REQUIRED)
if(NOT TARGET rtscalib::eigen_blas)
  add_library(rtscalib::eigen_blas INTERFACE IMPORTED)
  set_target_properties(rtscalib::eigen_blas PROPERTIES
    INTERFACE_COMPILE_DEFINITIONS EIGEN_USE_BLAS
    INTERFACE_LINK_LIBRARIES BLAS::BLAS
    # Every executable asks OpenBLAS for one thread per call (blas_threads.cc).
    INTERFACE_SOURCES
      "$<$<STREQUAL:$<TARGET_PROPERTY:TYPE>,EXECUTABLE>:${CMAKE_CURRENT_LIST_DIR}/blas_threads.cc>")
endif()
