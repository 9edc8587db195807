#include "cloudviewer/errors.h"
#include "internal.h"
namespace cloudviewer {
int run_window(const Options&, std::ostream&, std::ostream&) { throw InputError("window: not yet"); }
}
