# Flags, and the Debian packages the build needs (make deps).

BUILD ?= build
CC ?= cc
OPT ?= -O2
# -ffp-contract=off: no fused multiply-add unless we write one. Contraction
# changes rounding differently in different places, which breaks the
# guarantees the robust geometry tests check (watertight triangles, ray
# offsets), and makes results differ between compilers. Never -ffast-math:
# it assumes NaN and Inf never happen, so the NaN guards would be removed.
CFLAGS ?= $(OPT) -g
ALL_CFLAGS = -std=c11 -D_DEFAULT_SOURCE -Wall -Wextra -Wpedantic -ffp-contract=off -fopenmp \
             -MMD -MP $(SANITIZE_FLAGS) $(CFLAGS)
# common/ is two folders, core/ (the lecture's: vectors, rays, camera, image,
# the render loop) and program/ (what a program around it needs: flags,
# files, scene format, MPI, checkpoints); a common header is still "vec3.h".
# The core is compiled seeing only its own headers (mk/chapters.mk), so an
# include of the machinery from it fails to compile, not just the check.
COMMON_INCLUDES = -Icommon/core -Icommon/program
CPPFLAGS += $(COMMON_INCLUDES) -Ichapters $(PKG_CFLAGS)
LDFLAGS += -fopenmp $(SANITIZE_FLAGS)
LDLIBS += $(OPENEXR_LIBS) $(STB_LIBS) -lm
TEST_LDLIBS = $(CMOCKA_LIBS)

# Debian packages the build, the tests and the plots need (by name);
# python3 runs tools/exercise.py (make exercise, grade, and its test).
DEBIAN_PACKAGES := gcc make pkg-config libcmocka-dev libopenexr-dev libstb-dev gnuplot-nox python3

# The libraries' flags come from pkg-config. On a fresh machine neither
# pkg-config nor the .pc files exist when make reads this file: `make deps`
# installs them, and every compile waits for deps. So pkg-config is asked
# when a recipe first expands the flags, not before, and its answer is kept
# for the rest of the run: $(call pkg_config,VARIABLE,ARGUMENTS). If it
# fails (it says why on stderr) the flags are empty, with a warning; `make
# -n` before `make deps` only shows commands without them.
pkg_config = $(if $(filter simple,$(flavor $(1))),,$(eval $(1) := $(strip $(shell pkg-config $(2) || echo PKG_CONFIG_FAILED)))$(if \
  $(filter PKG_CONFIG_FAILED,$($(1))),$(warning pkg-config $(2) failed: make deps installs pkg-config and the libraries)$(eval $(1) :=)))$($(1))
PKG_CFLAGS = $(call pkg_config,PKG_CFLAGS,--cflags OpenEXR stb cmocka)
# The code uses OpenEXR's C API (openexr.h), which is all in OpenEXRCore;
# OpenEXR.pc also lists the C++ libraries, which are not linked.
OPENEXR_LIBS = $(or $(filter -L% -lOpenEXRCore%,$(call pkg_config,OPENEXR_PC_LIBS,--libs OpenEXR)),-lOpenEXRCore)
STB_LIBS = $(call pkg_config,STB_LIBS,--libs stb)
CMOCKA_LIBS = $(call pkg_config,CMOCKA_LIBS,--libs cmocka)

# MPI=1 (make mpi, mk/mpi.mk): common/program/mpi_split.c built against OpenMPI,
# whose flags come from its pkg-config file, ompi-c (libopenmpi-dev).
# Without it the same sources build the one-rank version: nothing of MPI
# is needed by `make`, `make test` or any other target.
ifdef MPI
MPI_CFLAGS = $(call pkg_config,MPI_CFLAGS,--cflags ompi-c)
MPI_LIBS = $(call pkg_config,MPI_LIBS,--libs ompi-c)
CPPFLAGS += -DRENDER_MPI $(MPI_CFLAGS)
LDLIBS += $(MPI_LIBS)
endif

.PHONY: deps
# Installs what is missing, by Debian package name, and says what it installed.
# The targets that need more (docs-deps, bench-deps, valgrind-deps, fuzz-deps)
# run it again with their packages, after this one: two apt-get at once
# (make -j) would fail on dpkg's lock.
deps:
	@if ! command -v dpkg-query >/dev/null 2>&1; then \
	  echo "note: not a Debian system; make sure these are installed: $(DEBIAN_PACKAGES)"; exit 0; fi; \
	missing=""; \
	for p in $(DEBIAN_PACKAGES); do \
	  dpkg-query -W -f='$${Status}\n' $$p 2>/dev/null | grep -q ' installed$$' || missing="$$missing $$p"; \
	done; \
	[ -z "$$missing" ] && exit 0; \
	sudo=""; [ "$$(id -u)" = 0 ] || sudo=sudo; \
	echo "installing Debian packages:$$missing"; \
	if $$sudo apt-get update && \
	   DEBIAN_FRONTEND=noninteractive $$sudo apt-get install -y --no-install-recommends $$missing; then \
	  echo "installed:$$missing"; \
	else \
	  echo "make deps: apt-get failed (its messages are above); install by hand:$$missing" >&2; exit 1; \
	fi
