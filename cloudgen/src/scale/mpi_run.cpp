// MPI generation: plan on every rank, balanced shares, bricks streamed to rank 0 in batches.
// Compiled with CLOUDGEN_HAVE_MPI when CMake finds MPI; otherwise every entry point says how to
// get an MPI build.
#include "cloudgen/mpi_run.h"

#include <sys/resource.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include "cloudgen/scale.h"

#ifdef CLOUDGEN_HAVE_MPI
#define OMPI_SKIP_MPICXX 1  // the C API only (OpenMPI's mpi.h would pull in its deprecated C++ bindings)
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace cloudgen::mpi {

int launcher_size() {
  for (const char* k : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "MPI_LOCALNRANKS"})
    if (const char* v = std::getenv(k)) return std::max(1, std::atoi(v));
  return 0;
}

#ifndef CLOUDGEN_HAVE_MPI

bool built_with_mpi() { return false; }
void init() {
  throw InputError("--mpi: this cloudgen was built without MPI (install Debian's openmpi-bin and libopenmpi-dev, "
                   "then reconfigure and rebuild); use `cloudgen plan` and `cloudgen merge` for farm tiles instead");
}
Result generate_vdb(const Preset&, const GenerateOptions&, const ExportOptions&, const std::vector<std::string>&) {
  init();
  return {};
}
void abort(int code) { std::exit(code); }
void finalize() {}

#else

namespace {

bool g_started = false;
constexpr int kTagData = 1, kTagDone = 2;
constexpr size_t kBatchBytes = size_t(8) << 20;  // a message of at most ~8 MiB of brick buffers

void check(int rc, const char* what) {
  if (rc != MPI_SUCCESS) {
    char msg[MPI_MAX_ERROR_STRING];
    int len = 0;
    MPI_Error_string(rc, msg, &len);
    throw IoError(std::string("MPI ") + what + " failed: " + std::string(msg, size_t(len)));
  }
}

uint64_t peak_rss() {
  struct rusage ru;
  getrusage(RUSAGE_SELF, &ru);
  return uint64_t(ru.ru_maxrss) * 1024;
}

struct Stored {
  size_t brick;
  BrickResult res;
};

// Batch layout: repeated [u64 brick][u64 channel mask][float arrays of the present channels].
void append(std::vector<char>& buf, const Stored& s) {
  uint64_t head[2] = {s.brick, 0};
  const std::vector<float>* ch[4] = {&s.res.density, &s.res.detail[0], &s.res.detail[1], &s.res.detail[2]};
  for (int c = 0; c < 4; ++c)
    if (!ch[c]->empty()) head[1] |= 1u << c;
  const size_t at = buf.size();
  buf.resize(at + sizeof head);
  std::memcpy(buf.data() + at, head, sizeof head);
  for (int c = 0; c < 4; ++c) {
    if (ch[c]->empty()) continue;
    const size_t n = ch[c]->size() * sizeof(float), p = buf.size();
    buf.resize(p + n);
    std::memcpy(buf.data() + p, ch[c]->data(), n);
  }
}

double g_insert_seconds = 0;  // rank 0: time spent adding bricks to the grids

void add_stored(VdbAssembler& out, const BrickPlan& plan, const std::array<uint32_t, 3>& r0, size_t brick,
                const float* const ch[4]) {
  const auto t0 = std::chrono::steady_clock::now();
  struct Timer {
    std::chrono::steady_clock::time_point t;
    ~Timer() { g_insert_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count(); }
  } timer{t0};
  const PlannedBrick& b = plan.bricks[brick];
  std::array<uint32_t, 3> lo, hi;
  for (int a = 0; a < 3; ++a) lo[a] = b.lo[a] - r0[a], hi[a] = b.hi[a] - r0[a];
  out.add(lo, hi, ch[0], {ch[1], ch[2], ch[3]});
}

/// Seconds since `t`, which moves on to now (one phase of the run timed after the other).
double lap(std::chrono::steady_clock::time_point& t) {
  const auto now = std::chrono::steady_clock::now();
  const double s = std::chrono::duration<double>(now - t).count();
  t = now;
  return s;
}

/// The plan of `p` as every rank sees it, each rank having decided its contiguous share.
BrickPlan shared_plan(const Preset& p, const GenerateOptions& go, int rank, int nranks) {
  // Every rank makes the same plan and the same split (both deterministic), so nothing but the
  // results travels.
  // Each rank decides a contiguous share of the plan; the decisions (2 flags and a cost per brick)
  // are exchanged, so the plan costs every rank 1/N of the bound, not all of it.
  BrickPlan plan = plan_bricks(p, go, 0, 0);
  const size_t nb = plan.bricks.size();
  std::vector<int> counts(static_cast<size_t>(nranks)), displs(static_cast<size_t>(nranks));
  for (int r = 0; r < nranks; ++r) {
    const size_t a = nb * size_t(r) / size_t(nranks), b = nb * size_t(r + 1) / size_t(nranks);
    displs[size_t(r)] = int(a), counts[size_t(r)] = int(b - a);
  }
  const size_t first = size_t(displs[size_t(rank)]), count = size_t(counts[size_t(rank)]);
  const BrickPlan part = plan_bricks(p, go, first, count);
  struct Decision {
    double cost;
    int32_t density, detail;
  };
  std::vector<Decision> all(nb), mine_d(count);
  for (size_t i = 0; i < count; ++i) {
    const PlannedBrick& b = part.bricks[first + i];
    mine_d[i] = {b.cost, b.density, b.detail};
  }
  MPI_Datatype dt;
  check(MPI_Type_contiguous(int(sizeof(Decision)), MPI_BYTE, &dt), "type");
  MPI_Type_commit(&dt);
  check(MPI_Allgatherv(mine_d.data(), int(count), dt, all.data(), counts.data(), displs.data(), dt, MPI_COMM_WORLD),
        "allgather of the plan");
  MPI_Type_free(&dt);
  for (size_t i = 0; i < nb; ++i) {
    plan.bricks[i].cost = all[i].cost;
    plan.bricks[i].density = all[i].density != 0;
    plan.bricks[i].detail = all[i].detail != 0;
  }
  return plan;
}

/// This rank's non-empty bricks of `mine`, in brick order (progress reported on rank 0 only).
std::vector<Stored> generate_share(const Preset& p, const BrickPlan& plan, const std::vector<size_t>& mine,
                                   const GenerateOptions& go, int rank, GenerateStats& stats) {
  std::mutex mtx;
  std::vector<Stored> kept;
  GenerateOptions opt = go;
  opt.progress = rank == 0 ? go.progress : nullptr;
  execute_plan(p, plan, &mine, opt, [&](size_t b, BrickResult& r) {
    if (!r.any_value) return;  // all-zero bricks add nothing to a sparse grid
    std::lock_guard<std::mutex> lock(mtx);
    kept.push_back({b, std::move(r)});
  }, &stats);
  std::sort(kept.begin(), kept.end(), [](const Stored& a, const Stored& b) { return a.brick < b.brick; });
  return kept;
}

/// Test hook: CLOUDGEN_TEST_KILL_RANK=R kills rank R mid-run, before it sends its bricks.
void test_kill_rank(int rank) {
  if (const char* k = std::getenv("CLOUDGEN_TEST_KILL_RANK")) {
    if (std::atoi(k) == rank) {
      std::fprintf(stderr, "rank %d: killed by CLOUDGEN_TEST_KILL_RANK before sending its bricks\n", rank);
      std::fflush(stderr);
      std::raise(SIGKILL);
    }
  }
}

/// Rank 0: adds its own bricks to `out`, freeing them.
void add_own_bricks(VdbAssembler& out, const BrickPlan& plan, std::vector<Stored>& kept) {
  for (const Stored& s : kept) {
    const float* ch[4] = {s.res.density.empty() ? nullptr : s.res.density.data(),
                          s.res.detail[0].empty() ? nullptr : s.res.detail[0].data(),
                          s.res.detail[1].empty() ? nullptr : s.res.detail[1].data(),
                          s.res.detail[2].empty() ? nullptr : s.res.detail[2].data()};
    add_stored(out, plan, plan.region_lo, s.brick, ch);
  }
  std::vector<Stored>().swap(kept);
}

/// Rank 0: adds the bricks of one received batch (see append) from rank `src` to `out`.
void add_batch(VdbAssembler& out, const BrickPlan& plan, const std::vector<char>& buf, int src) {
  size_t at = 0;
  while (at < buf.size()) {
    uint64_t head[2];
    std::memcpy(head, buf.data() + at, sizeof head);
    at += sizeof head;
    if (head[0] >= plan.bricks.size()) throw IoError("rank " + std::to_string(src) + " sent an unknown brick");
    const size_t cnt = plan.bricks[head[0]].count();
    const float* ch[4] = {nullptr, nullptr, nullptr, nullptr};
    for (int c = 0; c < 4; ++c)
      if (head[1] & (1u << c)) {
        ch[c] = reinterpret_cast<const float*>(buf.data() + at);  // MPI buffers are suitably aligned
        at += cnt * sizeof(float);
      }
    add_stored(out, plan, plan.region_lo, size_t(head[0]), ch);
  }
}

/// Rank 0: receives every other rank's stream, in rank order, into `out`; returns the bytes received.
uint64_t receive_bricks(VdbAssembler& out, const BrickPlan& plan, int nranks) {
  uint64_t received = 0;
  std::vector<char> buf;
  for (int src = 1; src < nranks; ++src) {
    for (;;) {
      MPI_Status st;
      check(MPI_Probe(src, MPI_ANY_TAG, MPI_COMM_WORLD, &st), "probe");
      int n = 0;
      MPI_Get_count(&st, MPI_BYTE, &n);
      buf.resize(size_t(n));
      check(MPI_Recv(buf.data(), n, MPI_BYTE, src, st.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE), "receive");
      received += uint64_t(n);
      if (st.MPI_TAG == kTagDone) break;
      add_batch(out, plan, buf, src);
    }
  }
  return received;
}

/// Ranks > 0: stream the kept bricks to rank 0 in batches of about kBatchBytes, freeing them.
void send_bricks(std::vector<Stored>& kept) {
  std::vector<char> buf;
  auto flush = [&] {
    if (buf.empty()) return;
    check(MPI_Send(buf.data(), int(buf.size()), MPI_BYTE, 0, kTagData, MPI_COMM_WORLD), "send");
    buf.clear();
  };
  for (Stored& s : kept) {
    append(buf, s);
    s.res = BrickResult{};  // free as it goes
    if (buf.size() >= kBatchBytes) flush();
  }
  flush();
  check(MPI_Send(nullptr, 0, MPI_BYTE, 0, kTagDone, MPI_COMM_WORLD), "send");
  std::vector<Stored>().swap(kept);
}

/// Per-rank figures to rank 0 for --stats: every rank's, in rank order, on rank 0; empty elsewhere.
std::vector<RankStats> gather_rank_stats(const RankStats& me, int rank, int nranks) {
  constexpr int kFields = 8 + 2 * kBrickWorkKinds;
  double mine_f[kFields] = {double(me.gen.bricks), double(me.gen.bricks_skipped), double(me.gen.detail_bricks),
                            double(me.gen.active_voxels), me.gen.seconds, double(me.sent_bricks), me.send_seconds,
                            double(me.peak_rss)};
  for (int k = 0; k < kBrickWorkKinds; ++k) {
    mine_f[8 + k] = double(me.gen.work_bricks[k]);
    mine_f[8 + kBrickWorkKinds + k] = me.gen.work_seconds[k];
  }
  std::vector<double> all(rank == 0 ? size_t(kFields) * nranks : 0);
  check(MPI_Gather(mine_f, kFields, MPI_DOUBLE, all.data(), kFields, MPI_DOUBLE, 0, MPI_COMM_WORLD), "gather");
  std::vector<RankStats> per_rank;
  if (rank != 0) return per_rank;
  for (int r = 0; r < nranks; ++r) {
    const double* f = &all[size_t(r) * kFields];
    RankStats s;
    s.gen.bricks = size_t(f[0]), s.gen.bricks_skipped = size_t(f[1]), s.gen.detail_bricks = size_t(f[2]);
    s.gen.active_voxels = size_t(f[3]), s.gen.seconds = f[4], s.sent_bricks = size_t(f[5]);
    s.send_seconds = f[6], s.peak_rss = uint64_t(f[7]);
    for (int k = 0; k < kBrickWorkKinds; ++k) {
      s.gen.work_bricks[k] = size_t(f[8 + k]);
      s.gen.work_seconds[k] = f[8 + kBrickWorkKinds + k];
    }
    per_rank.push_back(s);
  }
  return per_rank;
}

}  // namespace

bool built_with_mpi() { return true; }

void init() {
  if (g_started) return;
  int provided = 0;
  check(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "init");
  g_started = true;
}

void abort(int code) {
  if (g_started) MPI_Abort(MPI_COMM_WORLD, code);
  std::exit(code);
}

void finalize() {
  if (g_started) MPI_Finalize();
  g_started = false;
}

Result generate_vdb(const Preset& p, const GenerateOptions& go, const ExportOptions& eo,
                    const std::vector<std::string>& outputs) {
  init();
  Result res;
  MPI_Comm_size(MPI_COMM_WORLD, &res.ranks);
  MPI_Comm_rank(MPI_COMM_WORLD, &res.rank);
  const int rank = res.rank, nranks = res.ranks;
  g_insert_seconds = 0;
  auto t0 = std::chrono::steady_clock::now();

  const BrickPlan plan = shared_plan(p, go, rank, nranks);
  const std::vector<size_t> mine = balance_bricks(plan, nranks)[size_t(rank)];
  res.plan_seconds = lap(t0);

  RankStats me;
  std::vector<Stored> kept = generate_share(p, plan, mine, go, rank, me.gen);
  test_kill_rank(rank);

  // Gather: rank 0 adds its own bricks, then each other rank's stream in rank order.
  const Volume header = volume_header(p, plan);
  std::array<bool, 3> detail{};
  for (int c = 0; c < 3; ++c) detail[c] = plan.detail && p.channels[c + 1].enabled;
  std::unique_ptr<VdbAssembler> out;
  me.sent_bricks = kept.size();
  if (rank == 0) {
    out = std::make_unique<VdbAssembler>(header, detail, eo);
    add_own_bricks(*out, plan, kept);
    res.received_bytes = receive_bricks(*out, plan, nranks);
  } else {
    send_bricks(kept);
  }
  me.send_seconds = lap(t0);
  res.gather_seconds = me.send_seconds;
  me.peak_rss = peak_rss();

  res.per_rank = gather_rank_stats(me, rank, nranks);
  if (rank == 0) {
    res.active_voxels = out->generated_voxels();
    res.insert_seconds = g_insert_seconds;
    for (const std::string& o : outputs) out->write(o);
    res.write_seconds = lap(t0);
  }
  // Nobody leaves before rank 0 has written (or failed and aborted the job).
  check(MPI_Barrier(MPI_COMM_WORLD), "barrier");
  return res;
}

#endif

}  // namespace cloudgen::mpi
