#include "app/host/Mpi.h"

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <stdexcept>
#include <vector>

#ifdef SL_HAVE_MPI
// The C interface only (MPI's C++ bindings are deprecated and do not compile warning-free).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace sl {

namespace {

/// A launcher's variables: Open MPI's mpirun, PMI (MPICH, Slurm's srun --mpi=pmi2), PMIx
/// (srun --mpi=pmix, Open MPI 5).
bool launchedByMpi() {
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
        if (std::getenv(v)) return true;
    return false;
}

#ifdef SL_HAVE_MPI

class MpiCommunicator final : public Communicator {
  public:
    MpiCommunicator() {
        int provided = 0;
        MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
        MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
        MPI_Comm_size(MPI_COMM_WORLD, &size_);
    }
    ~MpiCommunicator() override {
        int finalized = 0;
        MPI_Finalized(&finalized);
        if (!finalized) MPI_Finalize();
    }
    MpiCommunicator(const MpiCommunicator&) = delete;
    MpiCommunicator& operator=(const MpiCommunicator&) = delete;

    int rank() const override { return rank_; }
    int size() const override { return size_; }

    double secondsInCollectives() const override { return seconds_; }

    void sum(std::span<double> v) const override {
        const Timed timed(seconds_);
        forChunks(v, [this](double* p, int n) {
            MPI_Reduce(rank_ == 0 ? MPI_IN_PLACE : p, p, n, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
            MPI_Bcast(p, n, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        });
    }
    void combine(std::span<double> v) const override {
        const Timed timed(seconds_);
        forChunks(v, [](double* p, int n) {
            MPI_Allreduce(MPI_IN_PLACE, p, n, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
        });
    }
    void gather(std::span<double> v, size_t begin, size_t end) const override {
        const Timed timed(seconds_);
        if (v.size() > static_cast<size_t>(INT_MAX) || begin > end || end > v.size())
            throw std::invalid_argument("MPI gather: a block outside the array, or over 2^31");
        const long long mine[2] = {static_cast<long long>(begin), static_cast<long long>(end)};
        std::vector<long long> blocks(2 * static_cast<size_t>(size_));
        MPI_Allgather(mine, 2, MPI_LONG_LONG, blocks.data(), 2, MPI_LONG_LONG, MPI_COMM_WORLD);
        std::vector<int> counts(static_cast<size_t>(size_)), displs(counts.size());
        for (size_t r = 0; r < counts.size(); ++r) {
            displs[r] = static_cast<int>(blocks[2 * r]);
            counts[r] = static_cast<int>(blocks[2 * r + 1] - blocks[2 * r]);
        }
        MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, v.data(), counts.data(), displs.data(),
                       MPI_DOUBLE, MPI_COMM_WORLD);
    }
    [[noreturn]] void abort(int code) const override {
        MPI_Abort(MPI_COMM_WORLD, code);
        std::_Exit(code);
    }

  private:
    int rank_ = 0, size_ = 1;
    mutable double seconds_ = 0;

    struct Timed {
        explicit Timed(double& total) : total_(total), start_(MPI_Wtime()) {}
        ~Timed() { total_ += MPI_Wtime() - start_; }
        Timed(const Timed&) = delete;
        Timed& operator=(const Timed&) = delete;
        double& total_;
        double start_;
    };

    /// MPI counts are ints: longer arrays go in pieces.
    template <class F>
    static void forChunks(std::span<double> v, F f) {
        for (size_t at = 0; at < v.size();) {
            const size_t n = std::min(v.size() - at, static_cast<size_t>(INT_MAX));
            f(v.data() + at, static_cast<int>(n));
            at += n;
        }
    }
};

#endif

}  // namespace

bool mpiBuilt() {
#ifdef SL_HAVE_MPI
    return true;
#else
    return false;
#endif
}

std::string mpiLibraryVersion() {
#ifdef SL_HAVE_MPI
    char text[MPI_MAX_LIBRARY_VERSION_STRING];
    int len = 0;
    MPI_Get_library_version(text, &len);
    std::string s(text, static_cast<size_t>(std::max(len, 0)));
    s = s.substr(0, s.find_first_of(",\n"));  // "Open MPI v4.1.4" without the build details
    return s;
#else
    return {};
#endif
}

std::unique_ptr<Communicator> worldCommunicator() {
#ifdef SL_HAVE_MPI
    if (launchedByMpi()) return std::make_unique<MpiCommunicator>();
#else
    // Several copies of a build without MPI would each run the whole job alone, racing for the
    // same output.
    for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
        if (launchedByMpi() && std::getenv(v) && std::atoi(std::getenv(v)) > 1)
            throw std::runtime_error(
                "this scratchlight was built without MPI, so it cannot run as MPI ranks: install "
                "libopenmpi-dev (scripts/install-deps) and build again, or run it as one process");
#endif
    return std::make_unique<SerialCommunicator>();
}

}  // namespace sl
