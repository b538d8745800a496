// Default options of the sanitizer runtimes, compiled into every executable of
// a sanitized build (RTSCALIB_SANITIZE; the README's test command), so that the
// tests and the rtscalib processes they start behave alike without any
// environment: the first undefined-behaviour report stops the process (and so
// fails the test), and LeakSanitizer skips only system libraries that keep
// process-lifetime allocations on purpose (Mesa/GLX/LLVM behind the renderer's
// OpenGL, X11, fontconfig, VTK's singletons). rtscalib's own code is never
// suppressed. Environment variables (ASAN_OPTIONS, ...) still override these.

// intercept_tls_get_addr=0: ASan then keeps no list of the dynamic TLS
// blocks (those of modules loaded with dlopen: Mesa's driver behind the
// renderer's OpenGL), and LeakSanitizer's exit-time scan does not walk them.
// GCC 12's runtime sometimes reads a stale entry of that list there ("DTLS
// 26 at 0x0000000028cd-...", then "Tracer caught signal 11"), and a test
// that had passed fails at its exit: now and then, most often with another
// test beside it (ShotsTest.PointBoardsRenderAndDetect in the CI runs of
// 2026-11-27; with the option no run crashed). What is lost: memory that
// nothing but a dlopen'ed module's thread-local variables points to could
// be reported as a leak; those modules are Mesa's, suppressed below.
//
// allocator_release_to_os_interval_ms=-1: the allocator keeps the memory its
// freed chunks held instead of returning it to the kernel every few
// seconds. A rendered photo session frees and allocates images, Jacobians
// and projections of megabytes all the time; what was returned came back
// as fresh zeroed pages (a million page faults in the photo-session test).
// Nothing is checked less; a process's resident memory stays at its peak
// (the one-board session's 1.7 -> 2.2 GB).
extern "C" const char* __asan_default_options() {
  return "detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:"
         "intercept_tls_get_addr=0:allocator_release_to_os_interval_ms=-1";
}

extern "C" const char* __ubsan_default_options() {
  return "print_stacktrace=1:halt_on_error=1";
}

extern "C" const char* __lsan_default_suppressions() {
  return "leak:libGLX_mesa.so\n"
         "leak:libGL.so\n"
         "leak:libGLdispatch.so\n"
         "leak:swrast_dri.so\n"
         "leak:libgallium\n"
         "leak:libLLVM\n"
         "leak:libX11.so\n"
         "leak:libxcb.so\n"
         "leak:libfontconfig.so\n"
         "leak:libvtk\n"
         "leak:libdbus\n";
}

// Mesa unloads its DRI driver (libgallium/swrast_dri) with dlclose before the
// process exits; LeakSanitizer then reports that driver's process-lifetime
// allocations from an "<unknown module>" that no suppression can name. In the
// sanitized executables modules stay loaded, so the suppressions above match.
extern "C" int dlclose(void*) { return 0; }
