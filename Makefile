# The whole project in one non-recursive make: this file names the main
# targets; the rules are in mk/, one file per concern.
#
#   make             build every chapter's library and program, and every test suite
#   make demo        install missing Debian packages, build, render every chapter
#   make test        build and run every cmocka suite and the script checks
#   make chNN        build and run chapter NN          (make ch01)
#   make test-chNN   build and run chapter NN's tests  (make test-ch01)
#   make sanitize    the test suites under AddressSanitizer + UndefinedBehaviorSanitizer
#   make test-seeds  every random test over 200 seeds: how many runs fail
#   make fp-contract-leaks  chapter 01 rebuilt with fused multiply-add: the watertight test leaks
#   make test-wide-bvh  the wide BVH's suite with 4 children per node instead of 8 (alias test-bvh4)
#   make valgrind    one small render of each chapter program under valgrind
#   make fuzz        run each parser's fuzz target for FUZZ_SECONDS
#   make mpi         the programs built against OpenMPI, in build/mpi/ (mpirun -np N splits a render)
#   make test-mpi    1, 2 and 3 MPI ranks make the image one process makes; a killed rank stops the run
#   make bench       every benchmark table in one run (quick; FULL=1 full): structures beside Embree, the path tracer
#                    on the benchmark scenes, also on Embree's kernels, Cycles at equal CPU time where blender is
#   make bench-cycles  install Debian's blender if missing, then Cycles at equal CPU time alone
#   make plots       draw every figure (gnuplot) from data the programs write
#   make docs        the book: one HTML page per chapter, woven by pandoc, in build/docs/
#   make test-docs   render every page of the book in headless Chromium and check it
#   make exercise CH=NN [EX=name]  hand out chapter NN's exercises (stubs); make solution CH=NN takes them back
#   make grade [CH=NN]  run the suites on your code: one table, exercise by exercise
#   make check-exercises  every exercise's stub fails a test and builds; make solution restores it
#   make excerpts    write the code each README's excerpts show again from the sources (after a change or a merge)
#   make deps        install the Debian packages the build needs that are missing
#   make clean       remove everything generated (build/)
#   make help        this list
#
#   mk/config.mk     flags, Debian packages (make deps)
#   mk/chapters.mk   common/, and per chapter: library, program, suite, chNN, test-chNN
#   mk/tests.mk      make test, sanitize, test-seeds, fp-contract-leaks, test-wide-bvh, valgrind, fuzz
#   mk/mpi.mk        make mpi, mpi-deps, test-mpi
#   mk/bench.mk      make bench
#   mk/plots.mk      make plots
#   mk/docs.mk       make docs, test-docs, excerpts, figures
#   mk/exercises.mk  make exercise, solution, grade, exercises, check-exercises
#
# Everything generated goes under build/.

.DEFAULT_GOAL := all
.DELETE_ON_ERROR:
.PHONY: help clean

include mk/config.mk
include mk/chapters.mk
include mk/tests.mk
include mk/mpi.mk
include mk/bench.mk
include mk/plots.mk
include mk/docs.mk
include mk/exercises.mk

help:
	@sed -n '4,/^# Everything/s/^# \{0,1\}//p' Makefile
	@echo "chapters: $(CHAPTERS)"

clean:
	rm -rf $(BUILD)
