#include "cloudgen/exit_codes.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <ios>
#include <iostream>
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

int finish_stdout(int code) {
  std::cout.flush();
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int e = errno;
  if (flushed && !std::ferror(stdout) && std::cout.good()) return code;
  // stdio does not keep the errno of the write that failed earlier: one more byte on the already
  // damaged output asks the system again (a full disk says so again).
  int why = e;
  if (!why && ::write(STDOUT_FILENO, "\n", 1) < 0) why = errno;
  std::fprintf(stderr, "I/O error: writing to standard output failed: %s; what was printed is incomplete\n",
               why ? std::strerror(why) : "the stream reported an error");
  return code == kExitOk ? kExitIo : code;
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
