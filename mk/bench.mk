# make bench: the acceleration structures timed beside Embree, the path
# tracer on the benchmark scenes, also on Embree's kernels, and Cycles at
# equal CPU time (figures and CSV under build/data/ and build/bench/).

.PHONY: bench bench-deps bench-cycles bench-cycles-deps

# The Embree harness lives in ../shared/anchors (beside this repository); it
# is built here, never copied in. Embree itself comes from Debian.
SHARED ?= ../shared
comma := ,
empty :=
space := $(empty) $(empty)

$(BUILD)/bin/bench_accel: $(BUILD)/obj/tests/bench_accel.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -o $@

$(BUILD)/bin/embree_bench: $(SHARED)/anchors/embree_bench.c | bench-deps
	@mkdir -p $(dir $@)
	$(CC) -O2 -std=c99 -Wall $< -o $@ -lembree3 -lm

# Chapter 09's path tracer with its rays traced by Embree beside ours
# (tests/bench_pt_embree.c): built only here, and only where Embree's
# header is installed (`make bench-deps`).
EMBREE_HEADER := $(wildcard /usr/include/embree3/rtcore.h)
$(BUILD)/bin/bench_pt_embree: $(BUILD)/obj/tests/bench_pt_embree.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -lembree3 -o $@

# The benchmark scenes' program (tests/bench_scenes.c): with Embree's rows
# where its header is, without them (and saying so) where not.
$(BUILD)/obj/tests/bench_scenes.o: CPPFLAGS += $(if $(EMBREE_HEADER),-DBENCH_EMBREE)
$(BUILD)/bin/bench_scenes: $(BUILD)/obj/tests/bench_scenes.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) $(if $(EMBREE_HEADER),-lembree3) -o $@
$(BUILD)/bin/bench_equal_time: $(BUILD)/obj/tests/bench_equal_time.o $(ALL_LIBS)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -o $@

# Every table in one run (tests/bench.sh): the structures against Embree
# size by size, A B A B; chapter 13's steps and the path tracer on Embree's
# kernels; the benchmark scenes (chapter 13, the same on Embree, chapter
# 09's MIS rung, 1 and 2 threads, taking turns); Cycles at equal CPU time
# where blender is installed. Quick by default (a few minutes on 2 cores),
# FULL=1 for the full sizes (about an hour on 2 cores). The Embree programs are built
# only where their sources (EMBREE_HARNESS) and header (EMBREE_HEADER) are;
# as prerequisites, not by a make inside the recipe, which make -n would run.
EMBREE_HARNESS := $(wildcard $(SHARED)/anchors/embree_bench.c)
BENCH_PROGRAMS := $(BUILD)/bin/bench_accel $(BUILD)/bin/13-production $(BUILD)/bin/bench_scenes \
                  $(BUILD)/bin/bench_equal_time $(if $(EMBREE_HARNESS),$(BUILD)/bin/embree_bench) \
                  $(if $(EMBREE_HEADER),$(BUILD)/bin/bench_pt_embree)
bench: $(BENCH_PROGRAMS)
	@sh tests/bench.sh $(BUILD) $(if $(FULL),full,quick) all

# Cycles at equal CPU time alone, after installing Debian's blender if it
# is missing (the only target that installs it).
bench-cycles: $(BUILD)/bin/bench_scenes $(BUILD)/bin/bench_equal_time | bench-cycles-deps
	@sh tests/bench.sh $(BUILD) $(if $(FULL),full,quick) cycles

bench-cycles-deps: deps
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="blender"

bench-deps: deps
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="libembree-dev"
