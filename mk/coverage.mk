# `make coverage`: the test suite built with --coverage in $(BUILD)/cov, then
# line and branch coverage of firmware/ and proto/ (gcovr). Fails when
# firmware/ falls below COV_LINE_MIN % of lines or COV_BRANCH_MIN % of
# branches. What stays uncovered and why: docs/coverage.md.

COV_BUILD := $(BUILD)/cov
COV_LINE_MIN ?= 95
COV_BRANCH_MIN ?= 85

.PHONY: coverage

# Reports go to files under the build: gcovr replaces its output file, and
# as root it would replace /dev/null with a regular file.
coverage:
	$(Q)mkdir -p $(COV_BUILD)
	$(Q)find $(COV_BUILD) -name '*.gcda' -delete 2>/dev/null || true
	$(Q)$(MAKE) --no-print-directory BUILD=$(COV_BUILD) COVERAGE=1 OPT=-O0 check > $(COV_BUILD).log 2>&1 \
		|| { tail -n 40 $(COV_BUILD).log; exit 1; }
	@echo "== firmware/"
	$(Q)gcovr -r . --object-directory $(COV_BUILD)/obj --filter 'firmware/' \
		--exclude-unreachable-branches --exclude-throw-branches -s --txt $(COV_BUILD)/firmware.txt
	@echo "== proto/"
	$(Q)gcovr -r . --object-directory $(COV_BUILD)/obj --filter 'proto/' \
		--exclude-unreachable-branches -s --txt $(COV_BUILD)/proto.txt
	@echo "== firmware/ per file: lines"
	$(Q)gcovr -r . --object-directory $(COV_BUILD)/obj --filter 'firmware/' \
		--exclude-unreachable-branches | grep '^firmware/'
	@echo "== firmware/ per file: branches"
	$(Q)gcovr -r . --object-directory $(COV_BUILD)/obj --filter 'firmware/' \
		--exclude-unreachable-branches -b | grep '^firmware/'
	$(Q)gcovr -r . --object-directory $(COV_BUILD)/obj --filter 'firmware/' \
		--exclude-unreachable-branches --fail-under-line $(COV_LINE_MIN) \
		--fail-under-branch $(COV_BRANCH_MIN) -o $(COV_BUILD)/check.txt
