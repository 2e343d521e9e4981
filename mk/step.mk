# mk/step.mk: STEP AP242 (issue 17). build/surf-convert, the test driver
# tests/cli/step.sh converts surfaces with (IGES <-> STEP by extension,
# through host/cf_surfio) until `cellfit convert` is in the command layer;
# `make all` builds it beside cellfit. `make test-step` runs the script alone.
ifneq ($(BOARD_CROSS),1)
all: surf-convert
endif
.PHONY: surf-convert test-step
surf-convert: $(BUILD)/surf-convert
$(BUILD)/surf-convert: $(BUILD)/tests/surf_convert.o $(HOST_OBJ) $(HAL_OBJ) $(FW_OBJ)
	$(CC) $(LDSAN) -o $@ $^ $(LIBS)

test-step: $(BUILD)/surf-convert $(BUILD)/cellfit
	@sh tests/cli/step.sh $(BUILD)/cellfit
