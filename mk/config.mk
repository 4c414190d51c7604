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
CPPFLAGS += -Icommon -Ichapters -I/usr/include/OpenEXR
LDFLAGS += -fopenmp $(SANITIZE_FLAGS)
LDLIBS += -lOpenEXRCore -lstb -lm
TEST_LDLIBS = -lcmocka

# Debian packages the build, the tests and the plots need (by name).
DEBIAN_PACKAGES := gcc make libcmocka-dev libopenexr-dev libstb-dev gnuplot-nox

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
	$$sudo apt-get update -qq && \
	DEBIAN_FRONTEND=noninteractive $$sudo apt-get install -y -qq --no-install-recommends $$missing >/dev/null && \
	echo "installed:$$missing"
