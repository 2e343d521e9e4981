# SPDX-License-Identifier: MIT
# mk/zlib.mk: zlib (Debian zlib1g-dev, scripts/deps.sh build group) for the
# PNG writer's deflate (host/cf_png.c); every binary that links host/ needs it.
LIBS += -lz
