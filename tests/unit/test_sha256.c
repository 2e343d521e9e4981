/* SPDX-License-Identifier: MIT */
/* test_sha256.c: cf_sha256 against the FIPS 180-4 examples (NIST's CSRC
 * example values): "abc", the empty string, the 448-bit message, a million
 * 'a'; fed whole, byte by byte and in odd pieces; a file against its bytes. */
#include "cf_err.h"
#include "cf_sha256.h"
#include "cf_test.h"
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static const char *const abc = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";
static const char *const empty = "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855";
static const char *const m448 = "abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq";
static const char *const h448 = "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1";
static const char *const hmil = "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0";

static void hex_pieces(const char *s, size_t n, size_t piece, char out[CF_SHA256_HEX])
{
    cf_sha256_t c;
    uint8_t d[32];
    cf_sha256_init(&c);
    for (size_t i = 0; i < n; i += piece)
        cf_sha256_update(&c, s + i, n - i < piece ? n - i : piece);
    cf_sha256_final(&c, d);
    for (int i = 0; i < 32; i++)
        snprintf(out + 2 * i, 3, "%02x", d[i]);
}

static void test_vectors(void **state)
{
    (void)state;
    char h[CF_SHA256_HEX];
    cf_sha256_hex("abc", 3, h);
    assert_string_equal(h, abc);
    cf_sha256_hex("", 0, h);
    assert_string_equal(h, empty);
    cf_sha256_hex(m448, strlen(m448), h);
    assert_string_equal(h, h448);
    const size_t pieces[] = {1, 7, 63, 64, 65};
    for (size_t k = 0; k < sizeof pieces / sizeof pieces[0]; k++) {
        hex_pieces(m448, strlen(m448), pieces[k], h);
        assert_string_equal(h, h448);
    }
}

static void test_million_a(void **state)
{
    (void)state;
    size_t n = 1000000;
    char *a = malloc(n), h[CF_SHA256_HEX];
    assert_non_null(a);
    memset(a, 'a', n);
    cf_sha256_hex(a, n, h);
    assert_string_equal(h, hmil);
    hex_pieces(a, n, 997, h);
    assert_string_equal(h, hmil);
    free(a);
}

static void test_file(void **state)
{
    (void)state;
    const char *dir = getenv("CF_TEST_TMP");
    char path[512], h[CF_SHA256_HEX];
    snprintf(path, sizeof path, "%s/sha256_abc.txt", dir ? dir : "/tmp");
    FILE *f = fopen(path, "wb");
    if (!f && dir) { /* the build's tmp folder may not exist yet */
        snprintf(path, sizeof path, "/tmp/cf_sha256_%ld.txt", (long)getpid());
        f = fopen(path, "wb");
    }
    assert_non_null(f);
    fputs(m448, f);
    fclose(f);
    assert_int_equal(cf_sha256_file(path, h), CF_OK);
    assert_string_equal(h, h448);
    remove(path);
    assert_int_equal(cf_sha256_file(path, h), CF_EIO);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_vectors),
        cmocka_unit_test(test_million_a),
        cmocka_unit_test(test_file),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
