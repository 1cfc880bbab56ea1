/* CHOLMOD on a system pfem exported as Matrix Market (issue 18): times
 * the analysis (ordering and symbolic factorisation), the numeric
 * factorisation and one solve, best of REPEAT runs, and prints the
 * factor's size, in the same format as `examples/factor_mtx.rs` prints
 * faer's, so that the two stand side by side on the same matrix.
 * Written for pfem. Build and run (Debian: libsuitesparse-dev):
 *   gcc -O2 -o cholmod_factor tools/cholmod_factor.c -I/usr/include/suitesparse -lcholmod
 *   ./cholmod_factor STEM.mtx [STEM_rhs.mtx] [REPEAT] [amd|default]
 * `tools/cholmod_side_by_side.sh` does the export, both runs and the build. */
#include <cholmod.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(int argc, char **argv)
{
  cholmod_common c;
  cholmod_sparse *a0, *a;
  cholmod_dense *b = NULL, *x, *r;
  cholmod_factor *l = NULL;
  FILE *f;
  int repeat = argc > 3 ? atoi(argv[3]) : 3, k;
  const char *method = argc > 4 ? argv[4] : "default";
  double t_an = 1e300, t_fa = 1e300, t_so = 1e300, t, one[2] = {1, 0}, minus[2] = {-1, 0};
  double fill = 0, rn, bn;

  if (argc < 2) {
    fprintf(stderr, "usage: %s STEM.mtx [STEM_rhs.mtx] [REPEAT] [amd|default]\n", argv[0]);
    return 2;
  }
  cholmod_start(&c);
  if (strcmp(method, "amd") == 0) {
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_AMD;
    c.postorder = 1;
  }
  f = fopen(argv[1], "r");
  if (!f) {
    perror(argv[1]);
    return 1;
  }
  a0 = cholmod_read_sparse(f, &c);
  fclose(f);
  if (!a0) {
    fprintf(stderr, "cannot read %s\n", argv[1]);
    return 1;
  }
  /* pfem writes both triangles ("general"): keep the lower one, symmetric. */
  a = a0->stype == 0 ? cholmod_copy(a0, -1, 1, &c) : a0;
  if (argc > 2 && strcmp(argv[2], "-") != 0 && (f = fopen(argv[2], "r"))) {
    b = cholmod_read_dense(f, &c);
    fclose(f);
  }
  if (!b) b = cholmod_ones(a->nrow, 1, CHOLMOD_REAL, &c);
  for (k = 0; k < repeat; k++) {
    if (l) cholmod_free_factor(&l, &c);
    t = now();
    l = cholmod_analyze(a, &c);
    t = now() - t;
    if (!l) return 1;
    if (t < t_an) t_an = t;
    t = now();
    if (!cholmod_factorize(a, l, &c) || c.status != CHOLMOD_OK) {
      fprintf(stderr, "factorisation failed (status %d)\n", c.status);
      return 1;
    }
    t = now() - t;
    if (t < t_fa) t_fa = t;
    t = now();
    x = cholmod_solve(CHOLMOD_A, l, b, &c);
    t = now() - t;
    if (t < t_so) t_so = t;
    if (k + 1 < repeat) cholmod_free_dense(&x, &c);
  }
  /* Residual ‖b − A x‖ / ‖b‖ (2-norms). */
  r = cholmod_copy_dense(b, &c);
  cholmod_sdmult(a, 0, minus, one, x, r, &c);
  rn = cholmod_norm_dense(r, 2, &c);
  bn = cholmod_norm_dense(b, 2, &c);
  fill = c.lnz;
  /* nnz(L): the entries the factor stores (a supernodal factor's blocks,
   * padding included, as faer's count is); exact: without padding. */
  printf("cholmod(%s) n %ld nnz(A) %ld nnz(L) %ld analyse %.4f s factorise %.4f s solve %.4f s "
         "residual %.2e exact nnz(L) %.0f\n",
         method, (long)a->nrow, (long)cholmod_nnz(a0, &c), (long)(l->is_super ? l->xsize : l->nzmax),
         t_an, t_fa, t_so, bn > 0 ? rn / bn : rn, fill);
  cholmod_free_dense(&r, &c);
  cholmod_free_dense(&x, &c);
  cholmod_free_dense(&b, &c);
  cholmod_free_factor(&l, &c);
  if (a != a0) cholmod_free_sparse(&a, &c);
  cholmod_free_sparse(&a0, &c);
  cholmod_finish(&c);
  return 0;
}
