# The chapters as assignments (tools/exercise.py; docs/design.md, "Exercises").
#
#   make exercise CH=NN [EX=name]   hand out chapter NN's exercises: stubs in place of the marked bodies
#   make solution CH=NN [EX=name]   the reference bodies back; a learner's own kept in .exercises/yours/
#   make grade [CH=NN]              run the suites on the learner's code: one table, exercise by exercise
#   make exercises                  list every exercise, its file and the section that explains it
#   make check-exercises            for every exercise: the stub builds without warnings, a test that
#                                   names it fails on it, a small render survives it, make solution
#                                   gives every file back as it was; then a planted exercise that no
#                                   test catches must be refused
#
# make chNN, while an exercise is handed out, also renders the reference
# implementation's picture with the same flags and prints how far the
# learner's is from it (tools/image_compare.c).

.PHONY: exercise solution grade exercises check-exercises exercise-deps

EXERCISE_TOOL = python3 tools/exercise.py
exercise_selection = --ch $(CH) $(if $(EX),--ex $(EX))
need_chapter = $(if $(CH),,$(error say which chapter: make $@ CH=NN, e.g. make $@ CH=01))

exercise: | exercise-deps
	$(need_chapter)
	@$(EXERCISE_TOOL) handout $(exercise_selection)

solution: | exercise-deps
	$(need_chapter)
	@$(EXERCISE_TOOL) solution $(exercise_selection)

grade: | exercise-deps
	@$(EXERCISE_TOOL) grade $(if $(CH),--ch $(CH)) --build $(BUILD)

exercises: | exercise-deps
	@$(EXERCISE_TOOL) list $(if $(CH),--ch $(CH))

check-exercises: | exercise-deps
	@$(EXERCISE_TOOL) check $(if $(CH),--ch $(CH)) $(if $(EX),--ex $(EX))
	@$(EXERCISE_TOOL) check --plant

# python3 is in the build's own package list (mk/config.mk).
exercise-deps: deps

# The picture comparison's program.
$(BUILD)/bin/image_compare: $(BUILD)/obj/tools/image_compare.o $(COMMON_LIB)
	@mkdir -p $(dir $@)
	$(CC) $(LDFLAGS) $^ $(LDLIBS) -o $@
