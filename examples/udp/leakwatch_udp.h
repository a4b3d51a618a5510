/*
 * leakwatch_udp.h: the leakwatch UDP sensor-stream format, version 2.
 *
 * One datagram = one rig sample, 80 bytes, LITTLE-ENDIAN, no padding.
 * (Version 1 is the first 72 bytes without temp_c; the receiver reads both.)
 * Send one datagram per sample to the address the acquisition stage listens
 * on (`acquisition --udp ADDR:PORT`, `leakwatch run --source udp://ADDR:PORT`).
 * The Rust side is frames/src/udp.rs; the table is in frames/README.md.
 *
 *   offset  field    type     meaning
 *        0  magic    u8[4]    "LWUD"
 *        4  version  u16      2
 *        6  flags    u16      bit0 x_sp present, bit1 f_load present,
 *                             bit2 end of stream, bit3 no sample (with bit2),
 *                             bit4 temp_c present
 *        8  seq      u64      sequence number, +1 per datagram
 *       16  t        f64      sample time, s
 *       24  u        f64      valve command, V (or raw counts, see below)
 *       32  x        f64      rod position, m
 *       40  p1       f64      chamber-1 pressure, Pa
 *       48  p2       f64      chamber-2 pressure, Pa
 *       56  x_sp     f64      spool position, m (read only with bit0)
 *       64  f_load   f64      load force, N (read only with bit1)
 *       72  temp_c   f64      oil temperature, deg C (read only with bit4)
 *
 * Channels may be sent as raw counts: the receiver computes
 * SI = gain * raw + offset per channel from the [udp] section of its config
 * (defaults gain 1, offset 0: the sender sends SI). t is always seconds.
 * Number the datagrams 0, 1, 2, ...: the receiver reports a jump as lost
 * samples, drops and counts duplicates and late (reordered) ones. Set
 * LWUD_FLAG_END_OF_STREAM on the last sample; a sender that learns of the end
 * later sends one datagram with LWUD_FLAG_END_OF_STREAM | LWUD_FLAG_NO_SAMPLE.
 *
 * Usage:
 *   uint8_t buf[LWUD_LEN];
 *   struct lwud_sample s = { .seq = n, .t = t, .u = u, .x = x, .p1 = p1, .p2 = p2,
 *                            .x_sp = NAN, .f_load = NAN, .temp_c = NAN, .flags = 0 };
 *   lwud_encode(&s, buf);
 *   sendto(fd, buf, LWUD_LEN, 0, (struct sockaddr *)&dst, sizeof dst);
 */
#ifndef LEAKWATCH_UDP_H
#define LEAKWATCH_UDP_H

#include <stdint.h>
#include <string.h>

#define LWUD_LEN 80u
#define LWUD_VERSION 2u
#define LWUD_MAGIC "LWUD"

#define LWUD_FLAG_X_SP_PRESENT (1u << 0)
#define LWUD_FLAG_F_LOAD_PRESENT (1u << 1)
#define LWUD_FLAG_END_OF_STREAM (1u << 2)
#define LWUD_FLAG_NO_SAMPLE (1u << 3)
#define LWUD_FLAG_TEMP_PRESENT (1u << 4)

/* The wire layout, for reading a datagram on a little-endian host. Fill a
 * struct lwud_sample and call lwud_encode to write one on any host. */
#pragma pack(push, 1)
struct lwud_datagram {
    uint8_t magic[4];
    uint16_t version;
    uint16_t flags;
    uint64_t seq;
    double t;
    double u;
    double x;
    double p1;
    double p2;
    double x_sp;
    double f_load;
    double temp_c;
};
#pragma pack(pop)

#if defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
_Static_assert(sizeof(struct lwud_datagram) == LWUD_LEN, "leakwatch datagram is 80 bytes");
#endif

/* One sample to send (host representation). */
struct lwud_sample {
    uint16_t flags; /* LWUD_FLAG_* */
    uint64_t seq;
    double t;      /* s */
    double u;      /* V or raw */
    double x;      /* m or raw */
    double p1;     /* Pa or raw */
    double p2;     /* Pa or raw */
    double x_sp;   /* m or raw; set LWUD_FLAG_X_SP_PRESENT */
    double f_load; /* N or raw; set LWUD_FLAG_F_LOAD_PRESENT */
    double temp_c; /* deg C or raw; set LWUD_FLAG_TEMP_PRESENT */
};

static inline void lwud_put_u16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xffu);
    p[1] = (uint8_t)(v >> 8);
}

static inline void lwud_put_u64(uint8_t *p, uint64_t v)
{
    for (int i = 0; i < 8; i++) {
        p[i] = (uint8_t)(v >> (8 * i));
    }
}

static inline void lwud_put_f64(uint8_t *p, double v)
{
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits); /* IEEE 754 binary64 */
    lwud_put_u64(p, bits);
}

/* Writes the LWUD_LEN little-endian bytes of `s` into `out` (any host byte order). */
static inline void lwud_encode(const struct lwud_sample *s, uint8_t out[LWUD_LEN])
{
    memcpy(out, LWUD_MAGIC, 4);
    lwud_put_u16(out + 4, (uint16_t)LWUD_VERSION);
    lwud_put_u16(out + 6, s->flags);
    lwud_put_u64(out + 8, s->seq);
    lwud_put_f64(out + 16, s->t);
    lwud_put_f64(out + 24, s->u);
    lwud_put_f64(out + 32, s->x);
    lwud_put_f64(out + 40, s->p1);
    lwud_put_f64(out + 48, s->p2);
    lwud_put_f64(out + 56, s->x_sp);
    lwud_put_f64(out + 64, s->f_load);
    lwud_put_f64(out + 72, s->temp_c);
}

#endif /* LEAKWATCH_UDP_H */
