// Generation over MPI ranks (Debian's OpenMPI): every rank plans the same bricks, generates its
// cost-balanced share with TBB inside, and streams its non-empty bricks to rank 0, which adds them
// to sparse VDB grids (never a dense copy of the volume) and writes the one-process file.
// No MPI types here; a build without MPI has the same functions, which say so.
#pragma once

#include <string>
#include <vector>

#include "cloudgen/generate.h"
#include "cloudgen/io.h"

namespace cloudgen::mpi {

/// True when this cloudgen was built with MPI (CMake found it).
bool built_with_mpi();
/// The number of ranks a launcher (mpirun / mpiexec / srun with PMI) announced in the
/// environment, 0 when this process was not started by one.
int launcher_size();

struct RankStats {
  GenerateStats gen;          ///< the bricks this rank generated
  size_t sent_bricks = 0;     ///< non-empty bricks streamed to rank 0 (rank 0: kept)
  double send_seconds = 0;    ///< time spent streaming them
  uint64_t peak_rss = 0;      ///< bytes
};
struct Result {
  int ranks = 1, rank = 0;
  std::vector<RankStats> per_rank;  ///< on rank 0 only: every rank, in rank order
  double plan_seconds = 0, gather_seconds = 0, write_seconds = 0;
  uint64_t active_voxels = 0;       ///< on rank 0
  uint64_t received_bytes = 0;      ///< on rank 0: brick buffers received from the other ranks
  double insert_seconds = 0;        ///< on rank 0: time adding bricks to the sparse grids
};

/// Starts MPI (once). Throws InputError when built without MPI.
void init();
/// Every rank calls this collectively; rank 0 writes each of `vdb_outputs` atomically. A rank
/// whose process dies makes the launcher end the job before rank 0 writes anything.
Result generate_vdb(const Preset& p, const GenerateOptions& go, const ExportOptions& eo,
                    const std::vector<std::string>& vdb_outputs);
/// Ends every rank of the job with `code` (after an error on one rank, so none waits forever).
[[noreturn]] void abort(int code);
void finalize();

}  // namespace cloudgen::mpi
