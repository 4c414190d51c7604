# make test and the other checks: the sanitizers, the random tests over many
# seeds, fused multiply-add, the 8-wide BVH, valgrind, fuzzing.

.PHONY: test sanitize test-seeds fp-contract-leaks test-wide-bvh test-bvh4 test-bvh8 valgrind valgrind-deps fuzz fuzz-deps

# Every suite, and every check that is a script, is a target of its own,
# run-NAME: it writes the output to $(BUILD)/tests/NAME.log and the exit
# status to NAME.status, and always succeeds, so that a failing suite stops
# none of the others and make -j runs them side by side. `make test` waits
# for all of them, then prints each log in a fixed order (suites, then
# scripts), adds up the counts and prints one summary line; it fails if
# anything failed. The scripts take the build directory: the programs fed
# bad input (tests/bad_input.sh), the hard-case catalog naming only tests
# that exist (tests/check_catalog.sh), each chapter including only common/
# and the chapters before it (tests/check_layering.sh), a warning before
# every render loop's long render (tests/long_render.sh), a render stopped by
# a signal and resumed from its checkpoint being the uninterrupted one
# (tests/resume.sh, chapter 09's program), every excerpt a README shows being
# its source's code, and a hand-edited one refused (tests/check_excerpts.sh),
# no chapter quoting a time typed by hand (tests/check_measured_numbers.sh),
# make exercise and make solution keeping every learner's body and giving
# the files back byte for byte (tests/exercise_tool.sh; the check that every
# exercise's stub fails its tests, which builds, is make check-exercises).
TEST_SCRIPTS := tests/bad_input.sh $(wildcard tests/check_catalog.sh) tests/check_layering.sh tests/long_render.sh \
                tests/resume.sh tests/check_excerpts.sh tests/check_measured_numbers.sh tests/exercise_tool.sh
SUITE_RUNS := $(patsubst $(BUILD)/tests/%,run-%,$(TESTS))
SCRIPT_RUNS := $(patsubst tests/%.sh,run-%,$(TEST_SCRIPTS))
.PHONY: $(SUITE_RUNS) $(SCRIPT_RUNS)

# Under -j, make starts them in this order: bad_input.sh's runs first, then
# the suites, each latest chapter first (the later chapters' take longer),
# so that the last to start are short and both cores finish together.
reverse = $(if $(1),$(call reverse,$(wordlist 2,$(words $(1)),$(1))) $(firstword $(1)))
test: $(SCRIPT_RUNS) $(call reverse,$(SUITE_RUNS))
	@passed=0; failed=0; bad=""; \
	for t in $(TESTS); do \
	  echo "== $$t"; cat $$t.log; status=$$(cat $$t.status 2>/dev/null); \
	  p=$$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' $$t.log | tail -1); \
	  f=$$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' $$t.log | tail -1); \
	  passed=$$((passed + $${p:-0})); failed=$$((failed + $${f:-0})); \
	  if [ "$$status" != 0 ]; then bad="$$bad $$t"; [ -n "$$f" ] || failed=$$((failed + 1)); fi; \
	done; \
	for s in $(TEST_SCRIPTS); do \
	  n=$$(basename $$s .sh); echo "== $$s"; cat $(BUILD)/tests/$$n.log; \
	  if [ "$$(cat $(BUILD)/tests/$$n.status 2>/dev/null)" = 0 ]; then passed=$$((passed + 1)); \
	  else failed=$$((failed + 1)); bad="$$bad $$s"; fi; \
	done; \
	echo; echo "$$passed passed, $$failed failed"; \
	if [ -n "$$bad" ]; then echo "failing suites:$$bad"; exit 1; fi

$(SUITE_RUNS): run-%: $(BUILD)/tests/%
	@$< > $<.log 2>&1; echo $$? > $<.status

$(filter-out run-bad_input,$(SCRIPT_RUNS)): run-%: tests/%.sh
	@mkdir -p $(BUILD)/tests
	@$< $(BUILD) > $(BUILD)/tests/$*.log 2>&1; echo $$? > $(BUILD)/tests/$*.status

# long_render.sh runs the programs.
run-long_render: $(PROGRAMS)
run-resume: $(BUILD)/bin/09-path-tracing
run-check_excerpts: docs/excerpts.sh docs/excerpts.awk

# bad_input.sh takes as long as all the suites together, so it runs once
# per program, run-bad_input-NN-name, side by side under -j; run-bad_input
# gathers them into one log, one status and one summary line: one check.
BAD_INPUT_RUNS := $(patsubst %,run-bad_input-%,$(CHAPTERS))
BAD_INPUT_DIR := $(BUILD)/tests/bad_input
.PHONY: $(BAD_INPUT_RUNS)
$(BAD_INPUT_RUNS): run-bad_input-%: $(BUILD)/bin/% tests/bad_input.sh
	@mkdir -p $(BAD_INPUT_DIR)
	@tests/bad_input.sh $(BUILD) $* > $(BAD_INPUT_DIR)/$*.log 2>&1; echo $$? > $(BAD_INPUT_DIR)/$*.status

run-bad_input: $(call reverse,$(BAD_INPUT_RUNS))
	@logs="$(patsubst %,$(BAD_INPUT_DIR)/%.log,$(CHAPTERS))"; \
	grep -hv '^bad input: ' $$logs > $(BUILD)/tests/bad_input.log; \
	cat $$logs | awk '/^bad input: /{c += $$3; f += $$5} \
	  END {printf "bad input: %d cases, %d failed ($(words $(CHAPTERS)) programs)\n", c, f}' >> $(BUILD)/tests/bad_input.log; \
	ok=$$(cat $(patsubst %,$(BAD_INPUT_DIR)/%.status,$(CHAPTERS)) | grep -cx 0); \
	[ "$$ok" = $(words $(CHAPTERS)) ]; echo $$? > $(BUILD)/tests/bad_input.status

# Every random test (those that take their seed from test_seed() in
# tests/test_support.h) over SEEDS other seeds, JOBS at a time: how many of
# the runs fail, per test. Not part of `make test` (about 40 minutes on
# two busy cores for 200 seeds).
SEEDS ?= 200
JOBS ?= 2
SEED_TESTS ?= .
test-seeds: $(TESTS)
	@tests/test_seeds.sh $(BUILD) $(SEEDS) $(JOBS) '$(SEED_TESTS)'

# The same suites built with AddressSanitizer and UndefinedBehaviorSanitizer,
# in a build directory of their own. Any report fails the run.
sanitize:
	@$(MAKE) --no-print-directory test BUILD=$(BUILD)/sanitize OPT=-O1 \
	  SANITIZE_FLAGS="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"

# What -ffp-contract=off protects: chapter 01's leak test built once more with
# fused multiply-add allowed and available (-mfma -ffp-contract=fast), in a
# build directory of its own. The watertight test's edge functions a*b - c*d
# then round differently for the two triangles of an edge, and rays leak.
# Reports the counts; its exit status is the leak test's (expected to fail).
fp-contract-leaks:
	@grep -q -w fma /proc/cpuinfo || { echo "this CPU has no FMA instructions: nothing to show"; exit 0; }
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/fp-contract CFLAGS="$(OPT) -g -mfma -ffp-contract=fast" \
	  $(BUILD)/fp-contract/tests/test_ch01 >/dev/null
	@echo "chapter 01 built with -mfma -ffp-contract=fast:"
	@TEST_FILTER='test_watertight_triangles*' $(BUILD)/fp-contract/tests/test_ch01 | grep -E 'leak|OK|FAILED'

# The wide BVH with another width than the default 8 (WIDE_BVH_WIDTH,
# wide_bvh.h; 4 unless told): its suite, WIDE_BVH_SUITE (the chapter that
# has wide_bvh.h), built in a build directory of its own, so that the other
# width keeps working. Compare speeds with $(BUILD)/wide-bvh4/bin/bench_accel
# beside $(BUILD)/bin/bench_accel. test-bvh4 is its name from when the tree
# was bvh4 (.ci/run calls it), test-bvh8 its name from when 4 was the default.
WIDE_BVH_SUITE ?= test_ch13
WIDE_BVH_TEST_WIDTH ?= 4
test-wide-bvh test-bvh4 test-bvh8:
	@$(MAKE) --no-print-directory BUILD=$(BUILD)/wide-bvh$(WIDE_BVH_TEST_WIDTH) \
	  CFLAGS="$(OPT) -g -DWIDE_BVH_WIDTH=$(WIDE_BVH_TEST_WIDTH)" \
	  $(BUILD)/wide-bvh$(WIDE_BVH_TEST_WIDTH)/tests/$(WIDE_BVH_SUITE) \
	  $(BUILD)/wide-bvh$(WIDE_BVH_TEST_WIDTH)/bin/bench_accel >/dev/null
	@$(BUILD)/wide-bvh$(WIDE_BVH_TEST_WIDTH)/tests/$(WIDE_BVH_SUITE)

# One small render of every chapter program under valgrind: no invalid reads
# or writes, no definite leaks. (OpenMP's thread pool keeps its stacks until
# exit, which valgrind calls "possibly lost"; those are not ours.)
# Each chapter's own flags keep its run short: small procedural meshes (04-06),
# few furnace bounces (07), the quick experiment (08), one sample (09).
VALGRIND_ARGS_01 :=
VALGRIND_ARGS_02 :=
VALGRIND_ARGS_03 :=
VALGRIND_ARGS_04 := --triangles 1024 --probe-rays 100
VALGRIND_ARGS_05 := --triangles 1024
VALGRIND_ARGS_06 := --triangles 1024
VALGRIND_ARGS_07 := --bounces 3
VALGRIND_ARGS_08 := --quick --runs 8 --max-log2n 6
VALGRIND_ARGS_09 := --spp 1 --max-depth 4
VALGRIND_ARGS_10 := --spp 1 --max-depth 2 --light-samples 1 --glossy-samples 2
VALGRIND_ARGS_11 := --spp 1 --max-depth 3
VALGRIND_ARGS_12 := --spp 2 --max-depth 3 --bootstrap 1000 --chains 8
# A chapter without VALGRIND_ARGS_NN runs with the common flags only.
valgrind: $(PROGRAMS) | valgrind-deps
	@mkdir -p $(BUILD)/valgrind
	@$(foreach c,$(CHAPTERS),\
	  echo "valgrind $(BUILD)/bin/$(c) $(VALGRIND_ARGS_$(call chapter_number,$(c)))" && \
	  valgrind -q --error-exitcode=1 --leak-check=full --errors-for-leak-kinds=definite --show-possibly-lost=no \
	    $(BUILD)/bin/$(c) --width 32 --height 24 --threads 2 --quiet $(VALGRIND_ARGS_$(call chapter_number,$(c))) \
	    --out $(BUILD)/valgrind/$(c).exr && ) \
	echo "valgrind: no errors and no definite leaks in $(words $(CHAPTERS)) programs"

valgrind-deps: deps
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="valgrind"

# One libFuzzer target per parser (tests/fuzz_NAME.c), built with clang and
# the address and undefined-behaviour sanitizers, run for FUZZ_SECONDS each
# (fuzz-NAME: each on its own, side by side under -j). Each links all of
# common/ and the generated version file (checkpoints and records name the
# version), and is built without OpenMP (common/ then runs on one thread):
# clang's OpenMP runtime is another package, and a parser has no threads
# to find. The corpus: $(BUILD)/fuzz/corpus_NAME (what the runs found,
# kept between runs), the seeds tests/fuzz/NAME/, the real files
# FUZZ_SEEDS_NAME names (the chapters' scene files), and what the target
# writes into $(BUILD)/fuzz/seeds_NAME when it starts (FUZZ_SEEDS_DIR: the
# checkpoint target writes real checkpoints through the real writer).
# -malloc_limit_mb: no input may make a target allocate more than that at
# once (a checkpoint's header may claim any size; the reader allocates this
# render's). Each run's log is $(BUILD)/fuzz/NAME.log; a crash fails the
# run, names the input libFuzzer saved, and shows the log's end.
FUZZ_SECONDS ?= 30
FUZZ_FLAGS ?= -malloc_limit_mb=256 -timeout=30
FUZZ_TARGETS := $(patsubst tests/fuzz_%.c,%,$(sort $(wildcard tests/fuzz_*.c)))
FUZZ_SEEDS_scene := $(wildcard chapters/*/scenes)
FUZZ_RUNS := $(addprefix fuzz-,$(FUZZ_TARGETS))
.PHONY: $(FUZZ_RUNS)

$(BUILD)/fuzz/fuzz_%: tests/fuzz_%.c $(COMMON_SRC) $(VERSION_SRC) | fuzz-deps
	@mkdir -p $(dir $@)
	clang -std=c11 -D_DEFAULT_SOURCE -g -O1 -ffp-contract=off -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all \
	  $(CPPFLAGS) $^ -o $@ $(LDLIBS)

$(FUZZ_RUNS): fuzz-%: $(BUILD)/fuzz/fuzz_%
	@mkdir -p $(BUILD)/fuzz/corpus_$* $(BUILD)/fuzz/seeds_$* $(BUILD)/fuzz/crashes
	@echo "fuzzing $* for $(FUZZ_SECONDS) s (seeds tests/fuzz/$*/ $(FUZZ_SEEDS_$*))"
	@FUZZ_SEEDS_DIR=$(BUILD)/fuzz/seeds_$* $< -max_total_time=$(FUZZ_SECONDS) -print_final_stats=1 $(FUZZ_FLAGS) \
	    -artifact_prefix=$(BUILD)/fuzz/crashes/$*- $(BUILD)/fuzz/corpus_$* $(BUILD)/fuzz/seeds_$* tests/fuzz/$* \
	    $(FUZZ_SEEDS_$*) > $(BUILD)/fuzz/$*.log 2>&1 \
	  || { tail -40 $(BUILD)/fuzz/$*.log; echo "fuzz_$* FOUND A CRASH (the input: $(BUILD)/fuzz/crashes/$*-*)"; exit 1; }
	@echo "fuzz_$*: $$(sed -n 's/^stat::number_of_executed_units: *//p' $(BUILD)/fuzz/$*.log) inputs in $(FUZZ_SECONDS) s, no crash"

fuzz: $(FUZZ_RUNS)

fuzz-deps: deps
	@$(MAKE) --no-print-directory deps DEBIAN_PACKAGES="clang libclang-rt-14-dev"
