// How the command line says a command's failure (apps/commands.hpp).
#include <iostream>
#include <new>

#include "apps/commands.hpp"
#include "core/error.hpp"

namespace floesim::apps {

int report_failure(std::exception_ptr failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    std::cerr << "floesim: error: " << e.what() << "\n";
    return 2;
  } catch (const RunError& e) {
    std::cerr << "floesim: run failed: " << e.what() << "\n";
    return 1;
  } catch (const std::bad_alloc&) {
    std::cerr << "floesim: run failed: out of memory\n";
    return 1;
  } catch (const std::exception& e) {  // a bug: said, not an abort
    std::cerr << "floesim: internal error: " << e.what() << "\n";
    return 1;
  } catch (...) {
    std::cerr << "floesim: internal error: an exception of unknown type\n";
    return 1;
  }
}

}  // namespace floesim::apps
