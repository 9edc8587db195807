// Safe output files (see cloudgen/output.h for the rules).
#include "cloudgen/output.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <map>
#include <streambuf>
#include <system_error>

#include "cloudgen/interrupt.h"
#include "cloudgen/printable.h"
#include "cloudgen/volume.h"

namespace cloudgen {
namespace fs = std::filesystem;

std::string system_error_text(int err) { return std::generic_category().message(err); }

namespace {

[[noreturn]] void throw_io(const std::string& path, const std::string& what, int err) {
  throw IoError(path + ": " + what + ": " + system_error_text(err));
}

/// write(2) until every byte is out; returns 0 or the errno of the failure.
int write_all(int fd, const char* p, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    if (w == 0) return EIO;
    p += w;
    n -= size_t(w);
  }
  return 0;
}

int close_checked(int fd) {
  if (::close(fd) != 0 && errno != EINTR) return errno;
  return 0;
}

/// A streambuf over a file descriptor that remembers the errno of the first failed write, so a
/// full disk is reported as "No space left on device" instead of a bare failbit.
class FdStreambuf : public std::streambuf {
 public:
  explicit FdStreambuf(int fd) : fd_(fd) { setp(buf_, buf_ + sizeof buf_); }
  int error() const { return err_; }
  int flush_all() {
    if (err_ == 0 && pptr() > pbase()) {
      err_ = write_all(fd_, pbase(), size_t(pptr() - pbase()));
      setp(buf_, buf_ + sizeof buf_);
    }
    return err_;
  }

 protected:
  int_type overflow(int_type ch) override {
    if (flush_all() != 0) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n >= std::streamsize(sizeof buf_)) {
      if (flush_all() != 0) return 0;
      err_ = write_all(fd_, s, size_t(n));
      return err_ ? 0 : n;
    }
    return std::streambuf::xsputn(s, n);
  }
  int sync() override { return flush_all() == 0 ? 0 : -1; }
  // OpenVDB writes placeholder grid offsets and seeks back to fill them in.
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override {
    if (flush_all() != 0) return pos_type(off_type(-1));
    const int whence = dir == std::ios_base::beg ? SEEK_SET : dir == std::ios_base::cur ? SEEK_CUR : SEEK_END;
    const off_t r = ::lseek(fd_, off_t(off), whence);
    if (r < 0) {
      err_ = errno;
      return pos_type(off_type(-1));
    }
    return pos_type(off_type(r));
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }

 private:
  int fd_;
  int err_ = 0;
  char buf_[1 << 16];
};

bool pid_alive(long pid) { return pid > 0 && (::kill(pid_t(pid), 0) == 0 || errno == EPERM); }

/// NAME as it appears in a temporary's name: at most 200 bytes, so `.NAME.tmp-PID-N` fits the
/// 255 bytes a file name may have for every legal NAME (an output of 242-255 bytes used to fail
/// with "File name too long").
std::string temp_stem(const std::string& name) { return name.size() <= 200 ? name : name.substr(0, 200); }

/// Removes `.NAME.tmp-PID-N` / `.NAME.bak-PID-N` files (and the temporary folders of
/// OutputBatch::new_folder, with what they hold) that a killed earlier run left in `dir`.
void remove_stale_temporaries(const fs::path& dir, const std::string& name) {
  std::error_code ec;
  for (const char* tag : {".tmp-", ".bak-"}) {
    const std::string prefix = "." + temp_stem(name) + tag;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      const std::string f = it->path().filename().string();
      if (f.rfind(prefix, 0) != 0) continue;
      const std::string rest = f.substr(prefix.size());
      const size_t dash = rest.find('-');
      if (dash == std::string::npos || dash == 0) continue;
      const std::string pid_text = rest.substr(0, dash);  // endp points into it: keep it alive
      char* endp = nullptr;
      const long pid = std::strtol(pid_text.c_str(), &endp, 10);
      if (!endp || *endp != '\0' || pid == long(::getpid()) || pid_alive(pid)) continue;
      std::error_code rm;
      if (it->is_directory(rm) && !it->is_symlink(rm)) fs::remove_all(it->path(), rm);
      else fs::remove(it->path(), rm);
    }
  }
}

enum class DestKind { Regular, WriteThrough };
struct Resolved {
  std::string path;  ///< after following symlinks
  DestKind kind = DestKind::Regular;
  bool exists = false;
  mode_t mode = 0;
};

/// Classifies the destination, following symlinks: the link stays and its target is written.
Resolved resolve_destination(const std::string& path) {
  auto refuse = [&](const struct stat& st, const std::string& shown) -> Resolved {
    const char* what = S_ISDIR(st.st_mode) ? "a folder" : S_ISBLK(st.st_mode) ? "a block device"
                       : S_ISSOCK(st.st_mode) ? "a socket" : "not a regular file";
    throw InputError(shown + ": is " + what +
                     "; outputs may be regular files (replaced atomically), character devices or FIFOs (written through)");
  };
  struct stat lst;
  if (::lstat(path.c_str(), &lst) != 0) {
    if (errno == ENOENT) return {path, DestKind::Regular, false, 0};
    throw_io(path, "cannot inspect the output path", errno);
  }
  if (!S_ISLNK(lst.st_mode)) {
    if (S_ISREG(lst.st_mode)) return {path, DestKind::Regular, true, mode_t(lst.st_mode & 07777)};
    if (S_ISCHR(lst.st_mode) || S_ISFIFO(lst.st_mode)) return {path, DestKind::WriteThrough, true, 0};
    return refuse(lst, path);
  }
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) {  // the link's final target exists
    // Devices and pipes are opened through the link (/dev/stdout -> /proc/self/fd/1 -> pipe).
    if (S_ISCHR(st.st_mode) || S_ISFIFO(st.st_mode)) return {path, DestKind::WriteThrough, true, 0};
    if (!S_ISREG(st.st_mode)) return refuse(st, path + " (a symbolic link)");
    std::error_code ec;
    const fs::path real = fs::canonical(path, ec);
    if (ec) throw_io(path, "cannot resolve the symbolic link", ec.value());
    return {real.string(), DestKind::Regular, true, mode_t(st.st_mode & 07777)};
  }
  // A dangling link: create the file it names.
  std::string p = path;
  for (int hop = 0; hop < 40; ++hop) {
    std::error_code ec;
    fs::path target = fs::read_symlink(p, ec);
    if (ec) throw_io(path, "cannot read the symbolic link", ec.value());
    if (target.is_relative()) target = fs::path(p).parent_path() / target;
    p = target.string();
    if (::lstat(p.c_str(), &lst) != 0) return {p, DestKind::Regular, false, 0};
    if (!S_ISLNK(lst.st_mode)) break;
  }
  throw InputError(path + ": too many levels of symbolic links");
}

std::atomic<unsigned> g_counter{0};

std::string unique_sibling(const fs::path& dir, const std::string& name, const char* tag) {
  return (dir / ("." + temp_stem(name) + tag + std::to_string(::getpid()) + "-" + std::to_string(g_counter++))).string();
}

}  // namespace

std::string file_identity(const std::string& path) {
  std::error_code ec;
  fs::path c = fs::canonical(path, ec);
  if (!ec) return c.string();
  fs::path p = fs::absolute(path, ec);
  fs::path parent = fs::weakly_canonical(p.parent_path(), ec);
  return (parent / p.filename()).lexically_normal().string();
}

// ---------------------------------------------------------------------------------------------

struct OutputBatch::Impl {
  struct Staged {
    std::string dest;      ///< as the user named it (for messages)
    Resolved target;       ///< where the bytes go
    int fd = -1;           ///< the temporary's descriptor
    bool anonymous = false;  ///< O_TMPFILE (no name until commit)
    std::string named_tmp;   ///< fallback temporary's path
    int folder = -1;         ///< index in folders_ when the file goes into a folder the batch creates
  };
  /// A folder new_folder() announced: its files are gathered in `tmp` at commit, then `tmp` is
  /// renamed to `path`.
  struct Folder {
    fs::path path;    ///< as the user named it, normalised, no trailing slash
    std::string tmp;  ///< the temporary sibling, once the commit made it
    bool published = false;
  };
  std::map<std::string, std::string> protected_;  ///< identity -> role
  std::map<std::string, std::string> claimed_;    ///< identity -> role
  std::vector<Staged> staged_;
  std::vector<Folder> folders_;

  ~Impl() { discard(); }
  void discard() {
    for (Staged& s : staged_) {
      if (s.fd >= 0) ::close(s.fd);
      if (!s.named_tmp.empty()) ::unlink(s.named_tmp.c_str());
    }
    staged_.clear();
    for (Folder& f : folders_) {
      std::error_code ec;
      if (!f.tmp.empty() && !f.published) fs::remove_all(f.tmp, ec);
    }
    folders_.clear();
  }
};

namespace {
fs::path normal_folder(const std::string& dir) {
  fs::path p = fs::path(dir).lexically_normal();
  if (p.has_parent_path() && p.filename().empty()) p = p.parent_path();  // "pack/" -> "pack"
  return p;
}
fs::path parent_or_dot(const fs::path& p) { return p.parent_path().empty() ? fs::path(".") : p.parent_path(); }
}  // namespace

OutputBatch::OutputBatch() : impl_(std::make_unique<Impl>()) {}
OutputBatch::~OutputBatch() = default;
size_t OutputBatch::staged() const { return impl_->staged_.size(); }

void OutputBatch::protect(const std::string& path, const std::string& role) {
  impl_->protected_[file_identity(path)] = role;
}

void OutputBatch::claim(const std::string& path, const std::string& role) {
  const Resolved r = resolve_destination(path);
  const std::string id = file_identity(r.path);
  if (auto it = impl_->protected_.find(id); it != impl_->protected_.end())
    throw InputError(path + ": writing " + role + " here would overwrite " + it->second +
                     "; choose another output name");
  if (const std::string input = protected_input_role(r.path); !input.empty())
    throw InputError(path + ": writing " + role + " here would overwrite " + input + "; choose another output name");
  if (auto it = impl_->claimed_.find(id); it != impl_->claimed_.end()) {
    if (it->second == role) return;  // the same claim twice (claim, then stage)
    throw InputError(path + ": would be written twice in this run, as " + it->second + " and as " + role +
                     "; give the outputs different names");
  }
  impl_->claimed_[id] = role;
}

void OutputBatch::new_folder(const std::string& dir, const std::string& role) {
  struct stat st;
  if (::lstat(dir.c_str(), &st) == 0) throw InputError(dir + ": " + role + " would be created here, but it exists");
  if (errno != ENOENT) throw_io(dir, "cannot inspect the output path", errno);
  const fs::path path = normal_folder(dir), parent = parent_or_dot(path);
  int err = 0;
  if (::stat(parent.c_str(), &st) != 0) err = errno;
  else if (!S_ISDIR(st.st_mode)) err = ENOTDIR;
  else if (::access(parent.c_str(), W_OK | X_OK) != 0) err = errno;
  if (err) throw InputError(dir + ": cannot create the folder: " + system_error_text(err));
  remove_stale_temporaries(parent, path.filename().string());
  impl_->folders_.push_back({path, "", false});
}

void OutputBatch::stage(const std::string& path, const std::function<void(const std::string&)>& fill) {
  stage_impl(path, fill, false);
}
void OutputBatch::stage_named(const std::string& path, const std::function<void(const std::string&)>& fill) {
  stage_impl(path, fill, true);
}

void OutputBatch::stage_impl(const std::string& path, const std::function<void(const std::string&)>& fill, bool named) {
  Impl::Staged s;
  s.dest = path;
  const fs::path in = fs::path(path).lexically_normal().parent_path();
  for (size_t i = 0; i < impl_->folders_.size(); ++i)
    if (in == impl_->folders_[i].path) s.folder = int(i);
  s.target = s.folder >= 0 ? Resolved{path, DestKind::Regular, false, 0} : resolve_destination(path);
  const std::string id = file_identity(s.target.path);
  if (impl_->protected_.count(id))
    throw InputError(path + ": would overwrite " + impl_->protected_[id] + "; choose another output name");
  if (const std::string input = protected_input_role(s.target.path); !input.empty())
    throw InputError(path + ": would overwrite " + input + "; choose another output name");
  for (const Impl::Staged& o : impl_->staged_)
    if (file_identity(o.target.path) == id)
      throw InputError(path + ": would be written twice in this run (also as " + o.dest + ")");
  const mode_t mode = s.target.exists && s.target.kind == DestKind::Regular ? s.target.mode : 0666;

  fs::path dir;
  if (s.target.kind == DestKind::WriteThrough) {
    std::error_code ec;
    dir = fs::temp_directory_path(ec);
    if (ec) dir = "/tmp";
  } else if (s.folder >= 0) {  // staged beside the folder, which does not exist before the commit
    dir = parent_or_dot(impl_->folders_[size_t(s.folder)].path);
    remove_stale_temporaries(dir, fs::path(s.target.path).filename().string());
  } else {
    dir = fs::path(s.target.path).parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir)) throw_io(path, "cannot create the folder " + dir.string(), ec ? ec.value() : ENOTDIR);
    remove_stale_temporaries(dir, fs::path(s.target.path).filename().string());
  }

  // An anonymous temporary vanishes by itself if the process dies; libraries that want a file
  // name reach it through /proc/self/fd.
  static const bool have_proc = ::access("/proc/self/fd", X_OK) == 0;
  if (have_proc && !named) {
    s.fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, mode);
    s.anonymous = s.fd >= 0;
  }
  if (s.fd < 0) {
    if (!named && errno != EOPNOTSUPP && errno != EISDIR && errno != EINVAL && errno != ENOENT && have_proc)
      throw_io(path, "cannot create a temporary file in " + dir.string(), errno);
    s.named_tmp = unique_sibling(dir, fs::path(s.target.path).filename().string(), ".tmp-");
    s.fd = ::open(s.named_tmp.c_str(), O_CREAT | O_EXCL | O_RDWR | O_CLOEXEC, mode);
    if (s.fd < 0) {
      const int e = errno;
      s.named_tmp.clear();
      throw_io(path, "cannot create a temporary file in " + dir.string(), e);
    }
  }
  if (s.target.exists && s.target.kind == DestKind::Regular) (void)::fchmod(s.fd, mode);
  const std::string tmp = s.anonymous ? "/proc/self/fd/" + std::to_string(s.fd) : s.named_tmp;
  if (named) {  // another program writes the path (and may replace it by rename): no descriptor kept
    ::close(s.fd);
    s.fd = -1;
  }
  try {
    fill(tmp);
    if (named) {
      struct stat st;
      if (::lstat(tmp.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) throw_io(path, "the writer left no file", ENOENT);
      s.fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
      if (s.fd < 0) throw_io(path, "cannot reopen the written file", errno);
      if (s.target.exists && s.target.kind == DestKind::Regular) (void)::fchmod(s.fd, mode);
    }
    if (::fsync(s.fd) != 0 && errno != EINVAL && errno != EBADF) throw_io(path, "cannot flush the written data to disk", errno);
  } catch (const IoError& e) {
    if (s.fd >= 0) ::close(s.fd);
    if (!s.named_tmp.empty()) ::unlink(s.named_tmp.c_str());
    // Writers name the path they were given; the user knows the destination.
    std::string msg = e.what();
    for (size_t k; (k = msg.find(tmp)) != std::string::npos;) msg.replace(k, tmp.size(), path);
    throw IoError(msg + "; the previous " + path + ", if any, is unchanged");
  } catch (...) {
    if (s.fd >= 0) ::close(s.fd);
    if (!s.named_tmp.empty()) ::unlink(s.named_tmp.c_str());
    throw;
  }
  impl_->claimed_.emplace(id, path);
  impl_->staged_.push_back(std::move(s));
}

namespace {

/// Opens a device or FIFO for writing. A FIFO with no reader is waited for without blocking, so a
/// signal still ends the wait (cloudgen/interrupt.h); the wait is said once on stderr.
int open_write_through(const std::string& path, const std::string& shown) {
  for (int tries = 0;; ++tries) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
    if (fd >= 0) {
      const int fl = ::fcntl(fd, F_GETFL);
      if (fl < 0 || ::fcntl(fd, F_SETFL, fl & ~O_NONBLOCK) < 0) {
        const int e = errno;
        ::close(fd);
        throw_io(shown, "cannot open for writing", e);
      }
      return fd;
    }
    if (errno != ENXIO) throw_io(shown, "cannot open for writing", errno);
    throw_if_interrupted();
    if (tries == 50) std::fprintf(stderr, "%s: waiting for a reader on this pipe (Ctrl-C ends the wait)\n", printable(shown).c_str());
    ::usleep(20000);
  }
}

}  // namespace

std::vector<std::string> OutputBatch::commit() {
  auto& staged = impl_->staged_;
  std::vector<std::string> written;
  // 1. Devices and FIFOs first: they cannot be rolled back, and a failure here leaves every
  //    regular output untouched.
  //    A signal's forced exit waits until the regular files are published whole (cloudgen/interrupt.h);
  //    a pipe is left as far as it was written.
  std::unique_ptr<CommitSection> whole;
  for (Impl::Staged& s : staged) {
    if (s.target.kind != DestKind::WriteThrough) continue;
    const int out = open_write_through(s.target.path, s.dest);
    note_publishing();
    std::vector<char> buf(1 << 20);
    int err = 0;
    for (off_t off = 0;;) {
      const int in = s.fd;
      ssize_t n = ::pread(in, buf.data(), buf.size(), off);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        err = errno;
        break;
      }
      if (n == 0) break;
      if ((err = write_all(out, buf.data(), size_t(n))) != 0) break;
      off += n;
    }
    const int cerr = close_checked(out);
    if (err || cerr) {
      std::string msg = s.dest + ": write failed: " + system_error_text(err ? err : cerr);
      msg += written.empty() ? "; no other output was written or replaced"
                             : "; already written through: " + [&] {
                                 std::string w;
                                 for (auto& x : written) w += (w.empty() ? "" : ", ") + x;
                                 return w;
                               }();
      throw IoError(msg);
    }
    written.push_back(s.dest);
  }
  // 2. Regular files: give each temporary a name, keep a hard link to the file it replaces, and
  //    rename. If any step fails, every file renamed so far is put back.
  whole = std::make_unique<CommitSection>();
  struct Done {
    std::string dest, backup;
    bool had_old;
    bool in_folder = false;  ///< inside a new folder's temporary: goes with it
  };
  std::vector<Done> done;
  auto& folders = impl_->folders_;
  auto rollback = [&]() -> std::string {
    std::string lost;
    for (Impl::Folder& f : folders) {  // new folders: taken back whole (the files in them with them)
      if (f.published && ::rename(f.path.c_str(), f.tmp.c_str()) != 0) lost += (lost.empty() ? "" : ", ") + f.path.string();
      else f.published = false;
      std::error_code ec;
      if (!f.published && !f.tmp.empty()) fs::remove_all(f.tmp, ec);
    }
    for (auto it = done.rbegin(); it != done.rend(); ++it) {
      if (it->in_folder) continue;
      if (!it->backup.empty()) {
        if (::rename(it->backup.c_str(), it->dest.c_str()) != 0) lost += (lost.empty() ? "" : ", ") + it->dest;
      } else if (!it->had_old) {
        ::unlink(it->dest.c_str());
      } else {
        lost += (lost.empty() ? "" : ", ") + it->dest;
      }
    }
    return lost;
  };
  // Each new folder that received a file gathers its files in a temporary sibling first.
  for (Impl::Folder& f : folders) {
    if (std::none_of(staged.begin(), staged.end(), [&](const Impl::Staged& s) { return s.folder == int(&f - folders.data()); }))
      continue;
    const std::string tmp = unique_sibling(parent_or_dot(f.path), f.path.filename().string(), ".tmp-");
    if (::mkdir(tmp.c_str(), 0777) != 0) {
      const int e = errno;
      const std::string lost = rollback();
      throw IoError(f.path.string() + ": cannot create the folder's temporary " + tmp + ": " + system_error_text(e) +
                    (lost.empty() ? "; every other output was left as it was" : "; could not restore the previous " + lost));
    }
    f.tmp = tmp;
  }
  for (Impl::Staged& s : staged) {
    if (s.target.kind != DestKind::Regular) continue;
    const std::string dest =
        s.folder >= 0 ? (fs::path(folders[size_t(s.folder)].tmp) / fs::path(s.target.path).filename()).string()
                      : s.target.path;
    const fs::path dir = fs::path(dest).parent_path().empty() ? fs::path(".") : fs::path(dest).parent_path();
    const std::string name = fs::path(dest).filename().string();
    std::string linked = s.named_tmp;
    auto fail = [&](const std::string& what, int err) {
      if (s.anonymous && !linked.empty()) ::unlink(linked.c_str());
      const std::string lost = rollback();
      throw IoError(s.dest + ": " + what + ": " + system_error_text(err) +
                    (lost.empty() ? "; every other output was left as it was"
                                  : "; could not restore the previous " + lost));
    };
    if (s.anonymous) {
      linked = unique_sibling(dir, name, ".tmp-");
      const std::string proc = "/proc/self/fd/" + std::to_string(s.fd);
      if (::linkat(AT_FDCWD, proc.c_str(), AT_FDCWD, linked.c_str(), AT_SYMLINK_FOLLOW) != 0) {
        const int e = errno;
        linked.clear();
        fail("cannot give the finished file a name", e);
      }
    }
    Done d{dest, "", false, s.folder >= 0};
    struct stat st;
    if (::lstat(dest.c_str(), &st) == 0 && S_ISREG(st.st_mode)) {
      d.had_old = true;
      const std::string bak = unique_sibling(dir, name, ".bak-");
      if (::link(dest.c_str(), bak.c_str()) == 0) d.backup = bak;
    }
    if (::rename(linked.c_str(), dest.c_str()) != 0) {
      const int e = errno;
      if (!d.backup.empty()) ::unlink(d.backup.c_str());
      fail("cannot move the finished file into place", e);
    }
    if (!s.anonymous) s.named_tmp.clear();  // now it is the destination
    done.push_back(d);
    written.push_back(s.dest);
  }
  // 3. The new folders, whole, each by one rename that never replaces what may have appeared
  //    under the name since the claim.
  auto fsync_dir = [](const fs::path& dir) {
    const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
      (void)::fsync(dfd);  // the renames survive a power cut; best effort
      ::close(dfd);
    }
  };
  for (Impl::Folder& f : folders) {
    if (f.tmp.empty()) continue;
    fsync_dir(f.tmp);
    int rc = ::renameat2(AT_FDCWD, f.tmp.c_str(), AT_FDCWD, f.path.c_str(), RENAME_NOREPLACE);
    if (rc != 0 && (errno == EINVAL || errno == ENOSYS)) {  // a filesystem without it: check, then rename
      struct stat st;
      if (::lstat(f.path.c_str(), &st) == 0) errno = EEXIST;
      else rc = ::rename(f.tmp.c_str(), f.path.c_str());
    }
    if (rc != 0) {
      const int e = errno;
      const std::string lost = rollback();
      throw IoError(f.path.string() + ": cannot move the finished folder into place: " + system_error_text(e) +
                    (lost.empty() ? "; no output was written or replaced" : "; could not restore the previous " + lost));
    }
    f.published = true;
    fsync_dir(parent_or_dot(f.path));
  }
  for (const Done& d : done) {
    if (!d.backup.empty()) ::unlink(d.backup.c_str());
    if (!d.in_folder) fsync_dir(parent_or_dot(fs::path(d.dest)));
  }
  impl_->discard();
  return written;
}

void atomic_write(const std::string& path, const std::function<void(const std::string&)>& fill) {
  OutputBatch b;
  b.stage(path, fill);
  b.commit();
}

void write_file_bytes(const std::string& path, const void* data, size_t n) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw_io(path, "cannot open for writing", errno);
  const int err = write_all(fd, static_cast<const char*>(data), n);
  const int cerr = close_checked(fd);
  if (err || cerr) throw_io(path, "write failed", err ? err : cerr);
}

void write_file_stream(const std::string& path, const std::function<void(std::ostream&)>& body) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) throw_io(path, "cannot open for writing", errno);
  FdStreambuf buf(fd);
  std::ostream os(&buf);
  try {
    body(os);
  } catch (...) {
    ::close(fd);
    throw;
  }
  os.flush();
  // Any failed operation counts: a failed seek sets only failbit, and the writes after it are
  // silently dropped.
  const int err = buf.flush_all() ? buf.error() : (os.fail() ? (buf.error() ? buf.error() : EIO) : 0);
  const int cerr = close_checked(fd);
  if (err || cerr) throw_io(path, "write failed", err ? err : cerr);
}

std::vector<uint8_t> read_file_bytes(const std::string& path, size_t max_bytes) {
  return read_input_bytes(path, "the input " + path, path, max_bytes);
}

}  // namespace cloudgen
