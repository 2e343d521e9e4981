# SPDX-License-Identifier: MIT
# mk/install.mk: what a plant installs (included by the top Makefile).
#   make install [PREFIX=/usr/local] [DESTDIR=STAGE]   programs, man pages,
#       the public header, libcellfit.a, cellfit.pc, bash completion, the
#       systemd unit, the example configuration and the documents (with
#       debian-depends: the runtime packages, dlopen'd ones included)
#   make uninstall [PREFIX=...] [DESTDIR=...]          removes exactly those
#   make lib      build/libcellfit.a (include/cellfit.h's implementation)
#   make man      build/man/cellfit.1, cellsim.1, cellfit.conf.5
#   test-install  (make test) installs into build/stage, builds examples/
#                 against it with pkg-config, runs them, renders every page

PREFIX ?= /usr/local
BINDIR ?= $(PREFIX)/bin
LIBDIR ?= $(PREFIX)/lib
INCLUDEDIR ?= $(PREFIX)/include
MANDIR ?= $(PREFIX)/share/man
DOCDIR ?= $(PREFIX)/share/doc/cellfit
COMPLETIONDIR ?= $(PREFIX)/share/bash-completion/completions
UNITDIR ?= $(PREFIX)/lib/systemd/system
# /etc for a system install (PREFIX=/usr), PREFIX/etc otherwise, as autoconf.
SYSCONFDIR ?= $(if $(filter /usr,$(PREFIX)),/etc,$(PREFIX)/etc)
INSTALL ?= install

API_OBJ := $(BUILD)/host/api/cellfit_api.o
LIBCELLFIT := $(BUILD)/libcellfit.a
# The library holds the fitter, the host library and the jobs and report
# layers (what the API calls); not the rig (hal) or the cell.
LIBCELLFIT_OBJ := $(API_OBJ) $(filter $(BUILD)/host/jobs/% $(BUILD)/host/report/%,$(HOSTLIB_OBJ)) \
	$(LIB_OBJ) $(FW_OBJ)
MAN_PAGES := $(BUILD)/man/cellfit.1 $(BUILD)/man/cellsim.1 $(BUILD)/man/cellfit.conf.5
DOCS := README.md LICENSE $(wildcard docs/*.md)

.PHONY: lib man install uninstall test-install

$(BUILD)/host/api/%.o: host/api/%.c
	@mkdir -p $(@D)
	$(CC) $(CF) $(JOBS_INC) -Iinclude -c $< -o $@

lib: $(LIBCELLFIT)
$(LIBCELLFIT): $(LIBCELLFIT_OBJ)
	@rm -f $@
	$(AR) rcs $@ $^

man: $(MAN_PAGES)
$(MAN_PAGES) &: $(BUILD)/cellfit $(BUILD)/cellsim scripts/man.sh
	sh scripts/man.sh $(BUILD)/cellfit $(BUILD)/cellsim $(BUILD)/man

$(BUILD)/dist/cellfit.pc: dist/cellfit.pc.in
	@mkdir -p $(@D)
	sed -e 's|@PREFIX@|$(PREFIX)|; s|@LIBDIR@|$(LIBDIR)|; s|@VERSION@|$(CF_VERSION)|' $< >$@
$(BUILD)/dist/cellfit.service: dist/cellfit.service.in
	@mkdir -p $(@D)
	sed -e 's|@BINDIR@|$(BINDIR)|; s|@SYSCONFDIR@|$(SYSCONFDIR)|; s|@DOCDIR@|$(DOCDIR)|' $< >$@
# The dlopen'd libraries' packages, as this build names them (mk/dl.mk):
# each @ID@ becomes ", package" (the first of a line without its comma), or
# nothing when the build has no such library.
$(BUILD)/dist/debian-depends: dist/debian-depends.in $(DL_HDR)
	@mkdir -p $(@D)
	awk 'NR == FNR { if ($$2 ~ /^HAL_DL_PACKAGE_/) { sub(/^HAL_DL_PACKAGE_/, "", $$2); \
	  gsub(/"/, "", $$3); p[$$2] = $$3 } next } \
	  /^[A-Z][a-z]*: / { while (match($$0, /@[A-Z0-9]+@/)) { id = substr($$0, RSTART + 1, RLENGTH - 2); \
	  $$0 = substr($$0, 1, RSTART - 1) (id in p ? ", " p[id] : "") substr($$0, RSTART + RLENGTH) } \
	  sub(/: , /, ": ") } { print }' $(DL_HDR) $< >$@
# Always remade: PREFIX may differ from the last run.
.PHONY: $(BUILD)/dist/cellfit.pc $(BUILD)/dist/cellfit.service

install: all lib man $(BUILD)/dist/cellfit.pc $(BUILD)/dist/cellfit.service \
	  $(BUILD)/dist/debian-depends
	$(INSTALL) -d $(DESTDIR)$(BINDIR) $(DESTDIR)$(LIBDIR)/pkgconfig $(DESTDIR)$(INCLUDEDIR) \
	  $(DESTDIR)$(MANDIR)/man1 $(DESTDIR)$(MANDIR)/man5 $(DESTDIR)$(DOCDIR)/examples \
	  $(DESTDIR)$(COMPLETIONDIR) $(DESTDIR)$(UNITDIR) $(DESTDIR)$(SYSCONFDIR)/cellfit
	$(INSTALL) -m 755 $(BUILD)/cellfit $(BUILD)/cellsim $(DESTDIR)$(BINDIR)/
	$(INSTALL) -m 644 $(LIBCELLFIT) $(DESTDIR)$(LIBDIR)/
	$(INSTALL) -m 644 $(BUILD)/dist/cellfit.pc $(DESTDIR)$(LIBDIR)/pkgconfig/
	$(INSTALL) -m 644 include/cellfit.h $(DESTDIR)$(INCLUDEDIR)/
	$(INSTALL) -m 644 $(BUILD)/man/cellfit.1 $(BUILD)/man/cellsim.1 $(DESTDIR)$(MANDIR)/man1/
	$(INSTALL) -m 644 $(BUILD)/man/cellfit.conf.5 $(DESTDIR)$(MANDIR)/man5/
	$(INSTALL) -m 644 $(DOCS) $(DESTDIR)$(DOCDIR)/
	$(INSTALL) -m 644 $(BUILD)/dist/debian-depends $(DESTDIR)$(DOCDIR)/
	$(INSTALL) -m 644 boards/linux-cell/cellfit.conf examples/*.c $(DESTDIR)$(DOCDIR)/examples/
	$(INSTALL) -m 644 dist/cellfit.bash-completion $(DESTDIR)$(COMPLETIONDIR)/cellfit
	$(INSTALL) -m 644 $(BUILD)/dist/cellfit.service $(DESTDIR)$(UNITDIR)/
	@# The configuration is the plant's once installed: never overwritten.
	@if [ -e $(DESTDIR)$(SYSCONFDIR)/cellfit/cellfit.conf ]; then \
	  echo "install: keeping $(DESTDIR)$(SYSCONFDIR)/cellfit/cellfit.conf"; else \
	  $(INSTALL) -m 644 boards/linux-cell/cellfit.conf $(DESTDIR)$(SYSCONFDIR)/cellfit/; fi

uninstall:
	rm -f $(DESTDIR)$(BINDIR)/cellfit $(DESTDIR)$(BINDIR)/cellsim \
	  $(DESTDIR)$(LIBDIR)/libcellfit.a $(DESTDIR)$(LIBDIR)/pkgconfig/cellfit.pc \
	  $(DESTDIR)$(INCLUDEDIR)/cellfit.h $(DESTDIR)$(MANDIR)/man1/cellfit.1 \
	  $(DESTDIR)$(MANDIR)/man1/cellsim.1 $(DESTDIR)$(MANDIR)/man5/cellfit.conf.5 \
	  $(DESTDIR)$(COMPLETIONDIR)/cellfit $(DESTDIR)$(UNITDIR)/cellfit.service
	rm -rf $(DESTDIR)$(DOCDIR)
	@# The configuration stays when it differs from the example (the plant's).
	@if cmp -s boards/linux-cell/cellfit.conf $(DESTDIR)$(SYSCONFDIR)/cellfit/cellfit.conf; then \
	  rm -f $(DESTDIR)$(SYSCONFDIR)/cellfit/cellfit.conf; \
	  rmdir $(DESTDIR)$(SYSCONFDIR)/cellfit 2>/dev/null || true; \
	else [ ! -e $(DESTDIR)$(SYSCONFDIR)/cellfit/cellfit.conf ] || \
	  echo "uninstall: keeping the changed $(DESTDIR)$(SYSCONFDIR)/cellfit/cellfit.conf"; fi

test-install: all
	@sh tests/pkg/install.sh $(BUILD)

TEST_EXTRA += test-install
