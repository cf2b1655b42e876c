# The figures in docs/figures (tools/figures.sh): made from the current
# build, each with a stamp of the files that determine it; make check fails
# naming a figure whose inputs changed since (tests/run_figures_tests.sh,
# which first proves that the check catches a change).
#
#   make figures      remake every figure and its stamp (Debian's
#                     python3-matplotlib under /usr/bin/python3)

.PHONY: figures
figures: $(BUILD)/vehicle-sim
	$(Q)tools/figures.sh make $(BUILD)

CHECK_SUITES += tests/run_figures_tests.sh
