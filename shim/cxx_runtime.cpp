// std::terminate for the C program (cxx_runtime.h): an uncaught std::bad_alloc is out of
// memory, any other uncaught exception is what it always was (a crash: abort).
// core headers have no extern "C" guards of their own: give them C linkage here.
extern "C" {
#include "core/memory.h"
}
#include "shim/cxx_runtime.h"

#include <cstdlib>
#include <exception>
#include <new>

namespace {

std::terminate_handler previous;

[[noreturn]] void on_terminate()
{
    // The exception being handled, if any: rethrown here only to learn its type (it is
    // the same object, so this allocates nothing new).
    if (std::exception_ptr current = std::current_exception()) {
        try {
            std::rethrow_exception(current);
        } catch (const std::bad_alloc &) {
            sl_memory_exhausted("std::bad_alloc that no caller could catch");
        } catch (...) {
        }
    }
    if (previous)
        previous();
    std::abort();
}

} // namespace

extern "C" void sl_cxx_terminate_install(void)
{
    std::terminate_handler old = std::set_terminate(on_terminate);
    if (old != on_terminate)
        previous = old;
}
