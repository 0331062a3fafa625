/*
 * Cortex-M4 cycle model for QEMU 7.2 TCG (plugin API version 1), for the crane firmware.
 *
 * Like icount.c it reports, for each interval between the instruction at `start=ADDR` and the
 * next one at `stop=ADDR`, a line "insns core art apess pess" to `out=FILE`:
 *   insns  executed instructions (exact);
 *   core   cycles with zero-wait memory: Cortex-M4 TRM (ARM DDI 0439B, table 3-1, and the FPU's
 *          table 7-1) per instruction class, pipeline refill P = 1 on a taken branch;
 *   art    core cycles with P = 2 plus the flash at 168 MHz (5 wait states, 128-bit lines)
 *          behind the ART accelerator: a 64-line instruction cache (fully associative, LRU)
 *          and the prefetch buffer (a sequential next-line miss only stalls for the part of
 *          the 6-cycle line read that the previous line's execution did not cover; a jump to
 *          a missing line stalls 5 cycles);
 *   apess  the pessimistic flash model with the ART on: P = 3, the same cache, but every miss
 *          stalls the full 5 wait states (no prefetch overlap) and every PC-relative (literal)
 *          load 5 more (as if the ART's data cache always missed);
 *   pess   P = 3 and no ART at all: every entry into another 128-bit line stalls 5 cycles and
 *          every PC-relative (literal) load 5 more: an upper bound for flash effects.
 * Class costs (core): data processing, MUL/MLA/UMULL/SMLAL, VADD/VSUB/VMUL/VCVT/VCMP/VMOV 1;
 * LDR/STR (each width) 2, LDRD/STRD 3, LDM/STM/PUSH/POP 1+N (N registers), VLDR/VSTR 2,
 * VLDM/VSTM/VPUSH/VPOP 1+N (N words); SDIV/UDIV 12 (the maximum of 2-12); VMLA/VMLS/VFMA
 * families 3; VDIV/VSQRT 14; B/BL/BX/BLX 1+P; TBB/TBH 2+P; a conditional branch (and
 * CBZ/CBNZ) 1, plus P when taken (taken = the next executed block does not start at its
 * fall-through address); a load or POP/LDM into PC is a taken branch (+P).
 * Not modelled: load/store pipelining (pessimistic: each load 2 cycles), interrupts, the
 * data-side flash cache other than literal loads in `pess`, bus contention.
 *
 *   gcc -O2 -shared -fPIC -o cycles.so cycles.c
 *   qemu-system-arm ... -plugin ./cycles.so,start=0x...,stop=0x...,out=cycles.txt
 *
 * The instruction mix (mnemonic classes, executed counts) goes to the end of the file.
 */
#include <ctype.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef uint64_t qemu_plugin_id_t;
typedef struct qemu_info_t qemu_info_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_CB_R_REGS, QEMU_PLUGIN_CB_RW_REGS };
enum qemu_plugin_op { QEMU_PLUGIN_INLINE_ADD_U64 };
typedef void (*tb_trans_cb)(qemu_plugin_id_t, struct qemu_plugin_tb *);
typedef void (*vcpu_udata_cb)(unsigned int, void *);
typedef void (*udata_cb)(qemu_plugin_id_t, void *);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t, tb_trans_cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *);
uint64_t qemu_plugin_tb_vaddr(const struct qemu_plugin_tb *);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *, size_t);
uint64_t qemu_plugin_insn_vaddr(const struct qemu_plugin_insn *);
size_t qemu_plugin_insn_size(const struct qemu_plugin_insn *);
char *qemu_plugin_insn_disas(const struct qemu_plugin_insn *);
void qemu_plugin_register_vcpu_insn_exec_inline(struct qemu_plugin_insn *, enum qemu_plugin_op,
                                                void *, uint64_t);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *, vcpu_udata_cb,
                                            enum qemu_plugin_cb_flags, void *);
void qemu_plugin_register_vcpu_tb_exec_cb(struct qemu_plugin_tb *, vcpu_udata_cb,
                                          enum qemu_plugin_cb_flags, void *);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t, udata_cb, void *);

__attribute__((visibility("default"))) int qemu_plugin_version = 1;

enum { M_CORE, M_ART, M_APESS, M_PESS, NM };
static const unsigned P[NM] = {1, 2, 3, 3};
enum { WS = 5, LINE_READ = WS + 1, CACHE_LINES = 64, MAX_LINES = 64 };

static uint64_t insns, cyc[NM], s_insns, s_cyc[NM], start_addr = 1, stop_addr = 1;
static FILE *out;

/* Instruction mix by class. */
enum { C_ALU, C_MUL, C_DIV, C_LD, C_ST, C_LDST2, C_MULTI, C_BR, C_CBR, C_FP, C_FPMAC, C_FPDIV,
       C_FPLS, NC };
static const char *cname[NC] = {"alu", "mul", "div", "load", "store", "ldrd/strd", "ldm/stm",
                                "branch", "cond-branch", "fp", "fp-mac", "fp-div/sqrt",
                                "fp-load/store"};
static uint64_t mix[NC];

struct tb_info {
    uint64_t start, fallthrough;
    int ends_cond;
    int nlines;
    uint64_t line[MAX_LINES];
    unsigned prev_cycles[MAX_LINES]; /* core cycles spent in the previous line of this block */
};

static const struct tb_info *prev_tb;
static uint64_t last_line = ~0ULL;
static uint64_t cache[CACHE_LINES], stamp[CACHE_LINES], clock_;

static int cache_access(uint64_t line)
{
    int lru = 0;
    for (int i = 0; i < CACHE_LINES; i++) {
        if (stamp[i] && cache[i] == line) {
            stamp[i] = ++clock_;
            return 1;
        }
        if (stamp[i] < stamp[lru])
            lru = i;
    }
    cache[lru] = line;
    stamp[lru] = ++clock_;
    return 0;
}

static void on_tb(unsigned int vcpu, void *u)
{
    (void)vcpu;
    const struct tb_info *t = u;
    int fell_through = prev_tb && t->start == prev_tb->fallthrough;
    if (prev_tb && prev_tb->ends_cond && !fell_through)
        for (int m = 0; m < NM; m++)
            cyc[m] += P[m];
    for (int i = 0; i < t->nlines; i++) {
        uint64_t l = t->line[i];
        if (i == 0 && l == last_line)
            continue;
        int sequential = i > 0 || (fell_through && l == last_line + 1);
        cyc[M_PESS] += WS;
        if (!cache_access(l)) {
            cyc[M_APESS] += WS;
            if (sequential) {
                unsigned covered = i > 0 ? t->prev_cycles[i] : 0;
                cyc[M_ART] += covered >= LINE_READ ? 0 : LINE_READ - covered;
            } else {
                cyc[M_ART] += WS;
            }
        }
        last_line = l;
    }
    prev_tb = t;
}

static void on_start(unsigned int vcpu, void *u)
{
    (void)vcpu; (void)u;
    s_insns = insns;
    memcpy(s_cyc, cyc, sizeof cyc);
}

static void on_stop(unsigned int vcpu, void *u)
{
    (void)vcpu; (void)u;
    fprintf(out, "%llu %llu %llu %llu %llu\n", (unsigned long long)(insns - s_insns),
            (unsigned long long)(cyc[M_CORE] - s_cyc[M_CORE]),
            (unsigned long long)(cyc[M_ART] - s_cyc[M_ART]),
            (unsigned long long)(cyc[M_APESS] - s_cyc[M_APESS]),
            (unsigned long long)(cyc[M_PESS] - s_cyc[M_PESS]));
}

/* Registers in a "{r4, r5-r7, pc}" list, in 32-bit words (d registers count 2). */
static unsigned reglist_words(const char *s, int *has_pc)
{
    const char *a = strchr(s, '{'), *b = a ? strchr(a, '}') : NULL;
    unsigned n = 0;
    *has_pc = 0;
    if (!a || !b)
        return 1;
    char buf[160];
    size_t len = (size_t)(b - a - 1) < sizeof buf - 1 ? (size_t)(b - a - 1) : sizeof buf - 1;
    memcpy(buf, a + 1, len);
    buf[len] = 0;
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        while (*tok == ' ')
            tok++;
        int words = tok[0] == 'd' ? 2 : 1;
        char *dash = strchr(tok, '-');
        if (strncmp(tok, "pc", 2) == 0)
            *has_pc = 1;
        if (dash && isdigit((unsigned char)tok[1]) && isdigit((unsigned char)dash[2]))
            n += (unsigned)(atoi(dash + 2) - atoi(tok + 1) + 1) * words;
        else
            n += words;
    }
    return n ? n : 1;
}

static int starts(const char *m, const char *p) { return strncmp(m, p, strlen(p)) == 0; }

static const char *conds[] = {"eq", "ne", "cs", "hs", "cc", "lo", "mi", "pl", "vs", "vc",
                              "hi", "ls", "ge", "lt", "gt", "le", NULL};

/* Is `m` (mnemonic without ".w/.n") "b" + condition? */
static int is_cond_branch(const char *m)
{
    if (!strcmp(m, "cbz") || !strcmp(m, "cbnz"))
        return 1;
    if (m[0] != 'b' || strlen(m) != 3)
        return 0;
    for (int i = 0; conds[i]; i++)
        if (!strcmp(m + 1, conds[i]))
            return 1;
    return 0;
}

/* Classifies one instruction: core cost without branch penalties, class, and flags. */
static unsigned classify(const char *dis, int *cls, int *branch, int *cond, int *literal)
{
    char m[32];
    size_t k = 0;
    while (*dis == ' ' || *dis == '\t')
        dis++;
    while (dis[k] && dis[k] != ' ' && dis[k] != '\t' && k < sizeof m - 1) {
        m[k] = (char)tolower((unsigned char)dis[k]);
        k++;
    }
    m[k] = 0;
    const char *ops = dis + k;
    char *dot = strchr(m, '.');
    char base[32];
    strcpy(base, m);
    if (dot && (!strcmp(dot, ".w") || !strcmp(dot, ".n")))
        base[dot - m] = 0;
    *branch = *cond = *literal = 0;
    int has_pc = 0;
    if (is_cond_branch(base)) {
        *cls = C_CBR; *branch = 1; *cond = 1;
        return 1;
    }
    if (!strcmp(base, "b") || !strcmp(base, "bl") || !strcmp(base, "bx") || !strcmp(base, "blx")) {
        *cls = C_BR; *branch = 1;
        return 1;
    }
    if (!strcmp(base, "tbb") || !strcmp(base, "tbh")) {
        *cls = C_BR; *branch = 1;
        return 2;
    }
    if (m[0] == 'v') {
        if (starts(m, "vldr") || starts(m, "vstr")) {
            *cls = C_FPLS;
            *literal = strstr(ops, "[pc") != NULL;
            return 2;
        }
        if (starts(m, "vpush") || starts(m, "vpop") || starts(m, "vldm") || starts(m, "vstm")) {
            *cls = C_FPLS;
            return 1 + reglist_words(ops, &has_pc);
        }
        if (starts(m, "vdiv") || starts(m, "vsqrt")) { *cls = C_FPDIV; return 14; }
        if (starts(m, "vmla") || starts(m, "vmls") || starts(m, "vnmla") || starts(m, "vnmls") ||
            starts(m, "vfma") || starts(m, "vfms") || starts(m, "vfnma") || starts(m, "vfnms")) {
            *cls = C_FPMAC; return 3;
        }
        *cls = C_FP;
        /* vmov between two core registers and a double register: 2 */
        if (starts(m, "vmov") && strchr(ops, ',') && strchr(strchr(ops, ',') + 1, ','))
            return 2;
        return 1;
    }
    if (starts(m, "push") || starts(m, "pop") || starts(m, "ldm") || starts(m, "stm")) {
        *cls = C_MULTI;
        unsigned n = reglist_words(ops, &has_pc);
        if (has_pc && (starts(m, "pop") || starts(m, "ldm")))
            *branch = 1;
        return 1 + n;
    }
    if (starts(m, "ldrd") || starts(m, "strd")) { *cls = C_LDST2; return 3; }
    if (starts(m, "ldr") || starts(m, "ldrex")) {
        *cls = C_LD;
        *literal = strstr(ops, "[pc") != NULL;
        while (*ops == ' ')
            ops++;
        if (starts(ops, "pc"))
            *branch = 1;
        return 2;
    }
    if (starts(m, "str")) { *cls = C_ST; return 2; }
    if (starts(m, "sdiv") || starts(m, "udiv")) { *cls = C_DIV; return 12; }
    if (starts(m, "mul") || starts(m, "mla") || starts(m, "mls") || starts(m, "smul") ||
        starts(m, "umul") || starts(m, "smla") || starts(m, "umla")) {
        *cls = C_MUL; return 1;
    }
    /* mov pc / add pc: a branch */
    while (*ops == ' ')
        ops++;
    if ((starts(m, "mov") || starts(m, "add")) && starts(ops, "pc"))
        *branch = 1;
    *cls = C_ALU;
    return 1;
}

static void on_trans(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    (void)id;
    size_t n = qemu_plugin_tb_n_insns(tb);
    struct tb_info *t = calloc(1, sizeof *t);
    if (!t)
        abort();
    t->start = qemu_plugin_tb_vaddr(tb);
    unsigned seg = 0;
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        uint64_t pc = qemu_plugin_insn_vaddr(insn);
        size_t size = qemu_plugin_insn_size(insn);
        char *dis = qemu_plugin_insn_disas(insn);
        if (!dis || !*dis) {
            fprintf(stderr, "cycles.c: no disassembly at 0x%llx\n", (unsigned long long)pc);
            abort();
        }
        int cls, branch, cond, literal;
        unsigned c = classify(dis, &cls, &branch, &cond, &literal);
        free(dis);
        /* lines touched (an instruction may straddle two) */
        for (uint64_t l = pc >> 4; l <= (pc + size - 1) >> 4; l++) {
            if (t->nlines == 0 || t->line[t->nlines - 1] != l) {
                if (t->nlines < MAX_LINES) {
                    t->prev_cycles[t->nlines] = seg;
                    t->line[t->nlines++] = l;
                }
                seg = 0;
            }
        }
        seg += c;
        if (pc == start_addr)
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_start, QEMU_PLUGIN_CB_NO_REGS, NULL);
        if (pc == stop_addr)
            qemu_plugin_register_vcpu_insn_exec_cb(insn, on_stop, QEMU_PLUGIN_CB_NO_REGS, NULL);
        qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &insns, 1);
        qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &mix[cls], 1);
        for (int m = 0; m < NM; m++) {
            uint64_t cm = c + ((branch && !cond) ? P[m] : 0) + (((m == M_PESS || m == M_APESS) && literal) ? WS : 0);
            qemu_plugin_register_vcpu_insn_exec_inline(insn, QEMU_PLUGIN_INLINE_ADD_U64, &cyc[m], cm);
        }
        if (i == n - 1) {
            t->ends_cond = cond;
            t->fallthrough = pc + size;
        }
    }
    /* The block callback runs before its instructions: the marker intervals see each block's
       flash stalls and the previous block's taken-branch refill at its start. */
    qemu_plugin_register_vcpu_tb_exec_cb(tb, on_tb, QEMU_PLUGIN_CB_NO_REGS, t);
}

static void at_exit(qemu_plugin_id_t id, void *u)
{
    (void)id; (void)u;
    fprintf(out, "TOTAL %llu %llu %llu %llu %llu\n", (unsigned long long)insns,
            (unsigned long long)cyc[M_CORE], (unsigned long long)cyc[M_ART],
            (unsigned long long)cyc[M_APESS],
            (unsigned long long)cyc[M_PESS]);
    for (int c = 0; c < NC; c++)
        fprintf(out, "MIX %s %llu\n", cname[c], (unsigned long long)mix[c]);
    fflush(out);
    if (out != stderr)
        fclose(out);
}

__attribute__((visibility("default"))) int
qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc, char **argv)
{
    (void)info;
    out = stderr;
    for (int i = 0; i < argc; i++) {
        if (strncmp(argv[i], "start=", 6) == 0)
            start_addr = strtoull(argv[i] + 6, NULL, 0) & ~1ULL;
        else if (strncmp(argv[i], "stop=", 5) == 0)
            stop_addr = strtoull(argv[i] + 5, NULL, 0) & ~1ULL;
        else if (strncmp(argv[i], "out=", 4) == 0) {
            out = fopen(argv[i] + 4, "w");
            if (!out)
                return -1;
        }
    }
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_trans);
    qemu_plugin_register_atexit_cb(id, at_exit, NULL);
    return 0;
}
