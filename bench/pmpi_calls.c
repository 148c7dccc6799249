/* bench/pmpi_calls.c: logs, on rank 0, the bytes each all-gather and all-to-all
 * receives (one line a call: kind, bytes received in all, and for an
 * all-gather the rank's own part), through MPI's profiling interface. A
 * measurement aid, not part of floesim: it tells which of a run's collectives
 * carry every floe's data (their size a multiple of the floe count), which the
 * summary's per-phase totals (`parallel.phase.*`) mix with the halos'.
 *
 *   mpicc -shared -fPIC -O2 -o /tmp/libpmpi_calls.so bench/pmpi_calls.c
 *   mpirun -np 2 -x LD_PRELOAD=/tmp/libpmpi_calls.so -x PMPI_LOG=/tmp/calls.log build/bin/floesim run ...
 */
#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

static FILE* out;
static int rank_ = -1;

static void open_log(void) {
  if (rank_ >= 0) return;
  PMPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  if (rank_ != 0) return;
  const char* path = getenv("PMPI_LOG");
  out = fopen(path ? path : "/tmp/pmpi_calls.log", "w");
}

static long long total(const int* counts, int ranks, MPI_Datatype type) {
  int size;
  PMPI_Type_size(type, &size);
  long long sum = 0;
  for (int r = 0; r < ranks; ++r) sum += counts[r];
  return sum * size;
}

int MPI_Allgatherv(const void* send, int send_count, MPI_Datatype send_type, void* receive, const int* counts,
                   const int* offsets, MPI_Datatype receive_type, MPI_Comm comm) {
  open_log();
  if (out) {
    int ranks, size;
    PMPI_Comm_size(comm, &ranks);
    PMPI_Type_size(send_type, &size);
    fprintf(out, "allgatherv %lld mine %lld\n", total(counts, ranks, receive_type), (long long)send_count * size);
  }
  return PMPI_Allgatherv(send, send_count, send_type, receive, counts, offsets, receive_type, comm);
}

int MPI_Allgather(const void* send, int send_count, MPI_Datatype send_type, void* receive, int receive_count,
                  MPI_Datatype receive_type, MPI_Comm comm) {
  open_log();
  if (out) {
    int ranks, size;
    PMPI_Comm_size(comm, &ranks);
    PMPI_Type_size(receive_type, &size);
    fprintf(out, "allgather %lld\n", (long long)receive_count * size * ranks);
  }
  return PMPI_Allgather(send, send_count, send_type, receive, receive_count, receive_type, comm);
}

int MPI_Alltoallv(const void* send, const int* send_counts, const int* send_offsets, MPI_Datatype send_type,
                  void* receive, const int* counts, const int* offsets, MPI_Datatype receive_type, MPI_Comm comm) {
  open_log();
  if (out) {
    int ranks;
    PMPI_Comm_size(comm, &ranks);
    fprintf(out, "alltoallv %lld\n", total(counts, ranks, receive_type));
  }
  return PMPI_Alltoallv(send, send_counts, send_offsets, send_type, receive, counts, offsets, receive_type, comm);
}

int MPI_Finalize(void) {
  if (out) fclose(out);
  out = NULL;
  return PMPI_Finalize();
}
