# SPDX-License-Identifier: MIT
# mk/scanfast.mk: the fast scan methods' targets (issue 19): make demo runs
# on the fly by default (scripts/demo.sh, DEMO_METHOD); demo-stop keeps the
# stop-and-go probe, demo-profiler runs cellsim's GigE Vision profiler.
.PHONY: demo-profiler demo-stop
demo-profiler:
	@sh scripts/deps.sh demo
	@$(MAKE) --no-print-directory all
	@DEMO_METHOD=profiler sh scripts/demo.sh $(BUILD)/cellfit

demo-stop:
	@sh scripts/deps.sh demo
	@$(MAKE) --no-print-directory all
	@DEMO_METHOD=stop sh scripts/demo.sh $(BUILD)/cellfit
