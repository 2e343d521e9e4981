/* SPDX-License-Identifier: MIT */
/* sim.h: cellsim, the simulated rig: a motion stage (Modbus holding
 * registers), a displacement probe (Modbus input registers and an ASCII
 * protocol) over a known part, faults on demand, and the servers that put
 * them on the wire (Modbus RTU on a tty, Modbus TCP, ASCII on a tty). The
 * register maps are hal_regmap.h's (docs/rig-devices.md). Times are
 * monotonic milliseconds; motion is evaluated from the clock when asked,
 * so nothing needs a thread. */
#ifndef SIM_H
#define SIM_H

#include "cf_part.h"
#include "nf_surf.h"
#include <stddef.h>
#include <stdint.h>

/* --- utilities (sim_util.c) --- */
double sim_now_ms(void);
typedef struct sim_rng {
    uint64_t s;
} sim_rng_t;
void sim_rng_seed(sim_rng_t *r, uint64_t seed, uint64_t stream);
double sim_urand(sim_rng_t *r); /* (0, 1) */
double sim_gauss(sim_rng_t *r); /* N(0, 1) */

/* --- wires --- */
enum { SIM_W_TCP = 1, SIM_W_RTU = 2, SIM_W_ASCII = 4 };

/* --- faults (sim_fault.c) --- */
typedef enum sim_fkind {
    SIM_F_CRC,        /* RTU: a CRC bit flipped; TCP: transaction id flipped; ASCII: garble */
    SIM_F_GARBLE,     /* one reply byte changed (RTU: data byte, so the CRC fails) */
    SIM_F_DROP,       /* one reply byte left out */
    SIM_F_SLOW,       /* reply held back MS ms */
    SIM_F_DISCONNECT, /* the line or server closed for MS ms */
    SIM_F_SILENT,     /* no reply at all */
    SIM_F_BUSY,       /* Modbus exception 06 (server busy) */
    SIM_F_NOSURF,     /* probe: out of range whatever is below */
    SIM_F_PROBEERR,   /* probe: ASCII ER,M0,01 / Modbus status error bit */
    SIM_F_STAGEFAULT, /* stage: the move faults half-way (drive fault latched) */
    SIM_F_NKINDS
} sim_fkind_t;

typedef struct sim_fault {
    sim_fkind_t kind;
    int wires;  /* SIM_W_* mask it applies to, 0 any */
    char mode;  /* 'n': the K-th event only, 'e': every K-th, 'p': probability P,
                 * 's': (wire kinds) the reply carrying stream entry K of each arming */
    long k;     /* for n and e */
    double p;   /* for p */
    double ms;  /* slow, disconnect */
    long count; /* events seen so far */
} sim_fault_t;

/* KIND[@WIRE]:WHEN[:MS], WHEN = nK | eK | pP (see cellsim --help). */
int sim_fault_parse(const char *spec, sim_fault_t *f, char *msg, size_t len);
const char *sim_fault_name(sim_fkind_t k);
/* Class of event a kind counts: 0 wire requests, 1 probe readings, 2 moves. */
int sim_fault_class(sim_fkind_t k);

#define SIM_MAX_FAULTS 32
typedef struct sim_faults {
    sim_fault_t f[SIM_MAX_FAULTS];
    int n;
    sim_rng_t rng;
    int verbose;
} sim_faults_t;

/* One event of a class on a wire: bit (1 << kind) set for every fault that
 * fires; *ms gets the largest MS of those. */
unsigned sim_faults_event(sim_faults_t *fs, int cls, int wire, double *ms);
/* A reply that carries the stream's entries lo .. lo + n - 1 (trigger
 * numbers since arming, as on the wire): the wire faults of mode 's' whose
 * K is among them fire (bits and *ms as sim_faults_event). Keyed to the
 * trigger number, not to a request count: the same entries are hit however
 * the host batches its reads (issue 19). */
unsigned sim_faults_stream(sim_faults_t *fs, int wire, uint16_t lo, int n, double *ms);

/* --- the stage (sim_stage.c) --- */
typedef struct sim_stage {
    int32_t tgt_raw[2];    /* target registers as written, um */
    double p0[2], p1[2];   /* motion from p0 (at t0) to p1 (at t1), mm */
    double t0, t1, tfault; /* ms; tfault < 0: no fault scheduled */
    int moving, homing, inpos;
    int homed, fault, estop, limit;
    uint16_t fault_code, moves, result;
    double lo[2], hi[2]; /* soft limits, mm */
    double speed;        /* mm/s */
    double settle_ms;
    double home[2];
    sim_faults_t *faults;
} sim_stage_t;

void sim_stage_init(sim_stage_t *st, sim_faults_t *fs);
void sim_stage_pos(sim_stage_t *st, double now, double xy[2]);
uint16_t sim_stage_status(sim_stage_t *st, double now);
/* Modbus holding registers: 0 or the exception code. */
int sim_stage_read(sim_stage_t *st, double now, int addr, int n, uint16_t *out);
int sim_stage_write(sim_stage_t *st, double now, int addr, int n, const uint16_t *in);
void sim_stage_set_estop(sim_stage_t *st, double now, int on);
void sim_stage_latch_fault(sim_stage_t *st, double now);

/* --- the part under the probe (sim_part.c) --- */
typedef struct sim_part {
    nf_surf_t s;  /* nominal */
    cf_part_t pt; /* its deviation: dent and warp (cf_part.h) */
    int ns;       /* seed grid ns x ns */
    double *seed; /* x, y, u, v per sample */
} sim_part_t;

/* The built-in part (cellfit gen's: 40 x 30 bicubic, cf_part_default) or
 * the first entity 128 of an IGES file. */
int sim_part_builtin(sim_part_t *p, char *msg, size_t len);
int sim_part_iges(sim_part_t *p, const char *path, char *msg, size_t len);
void sim_part_free(sim_part_t *p);
/* z of the real part (nominal + deviation) above (x, y): 0, or 1 when the
 * part is not below (x, y). */
int sim_part_z(const sim_part_t *p, double x, double y, double *z);
/* The same from a start uv (NaN: the nearest seed sample), which gets the
 * solution: along a profile each point starts from the last, so Newton
 * takes a step or two instead of a search of the seed grid. */
int sim_part_z_near(const sim_part_t *p, double x, double y, double uv[2], double *z);

/* --- the probe's streaming mode (sim_stream.c) --- */
typedef struct sim_fifo_ent {
    uint16_t seq, status;
    int32_t d_um, x_um, y_um;
} sim_fifo_ent_t;

/* The trigger input is simulated inside cellsim (there is no trigger box
 * on its wires): every period_us from arming, the probe measures at the
 * stage's position at that instant and latches it with the reading. */
typedef struct sim_stream {
    uint32_t period_us;      /* 0: not streaming */
    double t_arm;            /* ms */
    uint64_t k;              /* next trigger number */
    sim_fifo_ent_t *fifo;    /* cap entries (allocated at the first arming) */
    size_t cap, head, count; /* cap preset before the first arming: that size (0: 65536) */
    uint16_t overrun;
    double uv[2]; /* the part's parameters at the last reading (warm start) */
    /* The ASCII protocol's streaming (sim_ascii.c): entries go out as lines
     * on the connection that asked, the end line after the last. */
    uint32_t ascii_period; /* TP's value, us (0: 100) */
    int ascii;             /* 0 off, 1 streaming, 2 stopped: end line after the queue */
    int ascii_new;         /* MS just answered: the server records its connection */
    int ascii_conn;        /* that connection (sim_net.c) */
    /* The entries the last FIFO read popped (sim_net.c's 's' faults). */
    uint16_t popped_lo;
    int popped;
} sim_stream_t;

/* --- the probe (sim_probe.c) --- */
typedef struct sim_probe {
    const sim_part_t *part;
    sim_stage_t *stage;
    double z0;     /* beam origin height, mm (machine frame) */
    double off[2]; /* beam offset from the stage position in x, y, mm */
    double lo, hi; /* measuring range, mm */
    double noise;  /* Gaussian sigma, mm */
    sim_rng_t rng;
    uint16_t seq;
    sim_faults_t *faults;
    sim_stream_t stream;
} sim_probe_t;

/* One reading at the stage's present position: 0 and *d, 1 out of range,
 * 2 sensor error (fault). wire says which server asked (fault filters). */
int sim_probe_measure(sim_probe_t *pr, double now, int wire, double *d);
int sim_probe_read_input(sim_probe_t *pr, double now, int addr, int n, uint16_t *out);
/* The same reading with the stage at xy, the part from a warm start uv
 * (NaN: a fresh search; sim_part_z_near). */
int sim_probe_measure_at(sim_probe_t *pr, const double xy[2], int wire, double uv[2], double *d);

/* Streaming (sim_stream.c): triggers up to now taken (call before any
 * request is served, so the stage has not yet moved on); the holding
 * registers of the probe unit; the FIFO's input registers. Each returns 0
 * or a Modbus exception code. */
void sim_stream_catch_up(sim_probe_t *pr, double now);
int sim_stream_read_holding(sim_probe_t *pr, int addr, int n, uint16_t *out);
int sim_stream_write(sim_probe_t *pr, double now, int addr, int n, const uint16_t *in);
int sim_stream_read_fifo(sim_probe_t *pr, int addr, int n, uint16_t *out);
void sim_stream_free(sim_probe_t *pr);

/* --- Modbus (sim_mb.c) --- */
typedef struct sim_rig {
    sim_stage_t *stage;
    sim_probe_t *probe;
    int stage_unit, probe_unit;
} sim_rig_t;

uint16_t sim_crc16(const uint8_t *p, size_t n);
/* Answer one request PDU (function code first) for a unit: the reply PDU
 * in rsp (at most 256 bytes), its length returned; -1 for no reply (a unit
 * not here). busy: answer exception 06. */
int sim_mb_pdu(sim_rig_t *r, int wire, int unit, const uint8_t *req, size_t n, uint8_t *rsp,
               int busy);
/* Length of the RTU request frame at the start of buf (n bytes so far): the
 * full length, 0 when more bytes are needed to tell, -1 for a function code
 * whose length we cannot tell (the silence gap then ends it). */
int sim_rtu_frame_len(const uint8_t *buf, size_t n);

/* --- ASCII probe protocol (sim_ascii.c) --- */
/* Answer one request line (without its terminator) into out (with CR LF). */
size_t sim_ascii_answer(sim_probe_t *pr, double now, const char *line, char *out, size_t cap);
/* Streaming: queued entries as "SQ,..." lines into out (at most cap
 * bytes, whole lines), then once stopped and empty the "MQ,..." end line;
 * the bytes written. */
size_t sim_ascii_stream_lines(sim_probe_t *pr, double now, char *out, size_t cap);

#endif
