#include "cloudviewer/errors.h"
#include "internal.h"
namespace cloudviewer {
int run_bench(const Options&, const PreparedVolume&, std::ostream&, std::ostream&) { throw InputError("bench: not yet"); }
}
