# SPDX-License-Identifier: MIT
# mk/step.mk: build/surf-convert, the test driver tests/cli/step.sh makes its
# rational inputs with (IGES <-> STEP by extension through lib/cf_surfio,
# --rational SEED gives the net pseudo-random weights); the conversions under
# test go through `cellfit convert`. `make test-step` runs the script alone.
ifneq ($(BOARD_CROSS),1)
all: surf-convert
endif
.PHONY: surf-convert test-step
surf-convert: $(BUILD)/surf-convert
$(BUILD)/surf-convert: $(BUILD)/tests/surf_convert.o $(A_HOST) $(A_LIB) $(A_FW)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

test-step: $(BUILD)/surf-convert $(BUILD)/cellfit
	@sh tests/cli/step.sh $(BUILD)/cellfit
