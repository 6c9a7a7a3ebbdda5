#pragma once
/// \file
/// Where this process stands in a job started by an MPI launcher, read from the
/// launcher's environment before MPI itself is started, so that code without MPI (the
/// commands deciding who writes the bundle) knows it too. A process started alone is rank
/// 0 of 1.
namespace mgrl {

struct LaunchedProcess {
  int rank = 0;  ///< 0 for a process started alone
  int size = 1;  ///< processes in the job
  /// True when a launcher started this process (even as the only one: `mpirun -np 1`).
  bool byLauncher = false;
};

/// Reads Open MPI's `OMPI_COMM_WORLD_RANK` / `OMPI_COMM_WORLD_SIZE`, else the PMI
/// variables (`PMI_RANK` / `PMI_SIZE`, MPICH's and Slurm's `srun --mpi=pmi2`), else PMIx's
/// `PMIX_RANK` with Slurm's `SLURM_STEP_NUM_TASKS`. Throws mgrl::Error naming the variable
/// if one is set but is not a whole number, or the rank is not below the size.
LaunchedProcess launchedProcess();

}  // namespace mgrl
