# make mpi: every chapter program built against OpenMPI (common/program/mpi_split.h)
# in a build directory of its own, $(BUILD)/mpi/, so that the normal build
# needs no MPI. Run one over N processes with
#   mpirun -np 4 build/mpi/bin/09-path-tracing --spp 4096 --out build/out/ref.exr
# (mpirun --oversubscribe when N is more than the cores; as root, OpenMPI
# also wants --allow-run-as-root). make test-mpi checks that 1, 2 and 3
# ranks make the image one process makes, bit for bit, and that a rank
# killed in the middle stops the run with no image written.

.PHONY: mpi mpi-deps test-mpi

MPI_BUILD := $(BUILD)/mpi
MPI_PROGRAMS := $(patsubst $(BUILD)/%,$(MPI_BUILD)/%,$(PROGRAMS))

mpi: | mpi-deps
	@$(MAKE) --no-print-directory BUILD=$(MPI_BUILD) MPI=1 $(MPI_PROGRAMS)

mpi-deps: deps
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="libopenmpi-dev openmpi-bin"

# The plain programs beside the MPI ones: the test compares the two.
test-mpi: mpi $(BUILD)/bin/09-path-tracing $(BUILD)/bin/13-production
	@tests/mpi.sh $(BUILD) $(MPI_BUILD)
