/* The C++ runtime's last resort, for the C program: what std::terminate does.
 *
 * Every shim entry point catches every exception (CONVENTIONS: C++ only at the edge), but
 * some cannot be caught there: a std::bad_alloc thrown by a library's static constructor
 * while dlopen() runs it (OpenImageIO's string table under a tight [run]
 * memory_limit_mb), or by a destructor that allocates while the stack unwinds (OpenVDB's
 * Tree::clear). Both end in std::terminate, which by default aborts: the engine then saw
 * SIGABRT, a crash of ours, and quarantined the item as a scanlod bug (issue 34). */
#ifndef SCANLOD_SHIM_CXX_RUNTIME_H
#define SCANLOD_SHIM_CXX_RUNTIME_H

#ifdef __cplusplus
extern "C" {
#endif

/* Installs a std::terminate handler for the whole process (inherited by fork()ed
 * children): a std::bad_alloc (or an exception derived from it) ends in
 * sl_memory_exhausted() (core/memory.h: out of memory, exit 75 or the engine's report);
 * any other exception goes to the handler that was installed before (libstdc++'s, which
 * prints it and aborts). Call once, early in main(). */
void sl_cxx_terminate_install(void);

#ifdef __cplusplus
}
#endif

#endif
