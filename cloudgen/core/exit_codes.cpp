#include "cloudgen/exit_codes.h"

#include <filesystem>
#include <ios>
#include <new>

#include "cloudgen/errors.h"
#include "cloudgen/printable.h"
#include "noise3d/noise3d.h"

namespace cloudgen {

int exit_code_of(const std::exception_ptr& e) {
  try {
    std::rethrow_exception(e);
  } catch (const Cancelled&) {
    return kExitInterrupted;
  } catch (const InputError&) {
    return kExitInput;
  } catch (const noise3d::InvalidParameter&) {
    return kExitInput;
  } catch (const IoError&) {
    return kExitIo;
  } catch (const EnvironmentError&) {
    return kExitIo;
  } catch (const std::filesystem::filesystem_error&) {
    return kExitIo;
  } catch (const std::ios_base::failure&) {
    return kExitIo;
  } catch (const std::bad_alloc&) {
    return kExitIo;
  } catch (...) {
    return kExitInternal;
  }
}

const char* exit_kind(int code) {
  switch (code) {
    case kExitInput: return "error";
    case kExitIo: return "I/O error";
    case kExitInterrupted: return "interrupted";
    default: return "internal error";
  }
}

std::string error_message_of(const std::exception_ptr& e) {
  std::string what = "unknown exception";
  try {
    std::rethrow_exception(e);
  } catch (const std::bad_alloc&) {
    what = "out of memory (lower the resolution, or free memory)";
  } catch (const std::exception& x) {
    what = x.what();
  } catch (...) {
  }
  return std::string(exit_code_of(e) == kExitInternal ? "internal error: " : "error: ") + printable(what, true);
}

}  // namespace cloudgen
