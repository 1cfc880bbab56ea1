/* The few PETSc calls pfem needs, behind plain C types (the Rust side
 * cannot name MPI_Comm, whose type depends on the MPI library PETSc was
 * built with, nor PetscInt, whose width depends on PETSc's configuration).
 * Written for pfem; see src/lib.rs for the solver it serves. */
#include <petscksp.h>
#include <stdint.h>
#include <string.h>

/* The values cross as double: a complex or single-precision PETSc would
 * read them as something else. */
#if defined(PETSC_USE_COMPLEX) || !defined(PETSC_USE_REAL_DOUBLE)
#error "pfem's PETSc backend needs a real, double-precision PETSc (PetscScalar = double)"
#endif

/* The largest PetscInt (its width is PETSc's configuration). */
#if defined(PETSC_INT_MAX)
#define PFEM_INT_MAX PETSC_INT_MAX
#else
#define PFEM_INT_MAX PETSC_MAX_INT
#endif

static void message(PetscErrorCode code, const char *what, char *msg, size_t len)
{
  const char *text = NULL;
  if (!msg || len == 0) return;
  PetscErrorMessage(code, &text, NULL);
  snprintf(msg, len, "%s: PETSc error %d (%s)", what, (int)code, text ? text : "no text");
}

#define TRY(call, what)                 \
  do {                                  \
    PetscErrorCode e_ = (call);         \
    if (e_) {                           \
      message(e_, what, msg, len);      \
      code = e_;                        \
      goto done;                        \
    }                                   \
  } while (0)

/* Initialises PETSc once per process (no command-line arguments; PETSc's
 * own signal handlers are left out, errors are returned, not printed). */
int pfem_petsc_init(char *msg, size_t len)
{
  PetscBool initialised = PETSC_FALSE;
  PetscErrorCode code = 0;
  PetscInitialized(&initialised);
  if (initialised) return 0;
  TRY(PetscOptionsSetValue(NULL, "-no_signal_handler", NULL), "PetscOptionsSetValue");
  TRY(PetscInitializeNoArguments(), "PetscInitializeNoArguments");
  TRY(PetscPushErrorHandler(PetscReturnErrorHandler, NULL), "PetscPushErrorHandler");
done:
  return (int)code;
}

/* One KSP on one matrix, kept so that several right-hand sides share
 * its set-up (the solver's refinement passes). */
typedef struct {
  PetscOptions opts;
  Mat          K;
  Vec          vb, vy;
  KSP          ksp;
  IS           isv, isp;
} pfem_ksp;

static void destroy(pfem_ksp *h)
{
  /* Clean-up errors are not reported over the first one. */
  if (!h) return;
  if (h->ksp) KSPDestroy(&h->ksp);
  if (h->isv) ISDestroy(&h->isv);
  if (h->isp) ISDestroy(&h->isp);
  if (h->vb) VecDestroy(&h->vb);
  if (h->vy) VecDestroy(&h->vy);
  if (h->K) MatDestroy(&h->K);
  if (h->opts) PetscOptionsDestroy(&h->opts);
  PetscFree(h);
}

void pfem_petsc_destroy(pfem_ksp *h) { destroy(h); }

/* Whether PETSc was configured with hypre. */
int pfem_petsc_has_hypre(void)
{
#if defined(PETSC_HAVE_HYPRE)
  return 1;
#else
  return 0;
#endif
}

/* Sets up a KSP on the square CSR matrix K of n rows (64-bit indices on
 * the Rust side, converted to PetscInt here). The first nv unknowns form
 * the field "v" and the rest the field "p" of a PCFIELDSPLIT, with block
 * size bs on "v" (nv = n: no split). `options` (PETSc options, prefix
 * -pfem_) are the options database of this KSP alone (pushed while it is
 * configured and used), so that two solvers do not see each other's.
 * Returns 0 and *out, or a PETSc error code (text in msg). */
int pfem_petsc_create(int64_t n, int64_t nv, int64_t bs, const int64_t *ptr, const int64_t *idx,
                      const double *val, const char *options, pfem_ksp **out, char *msg,
                      size_t len)
{
  PetscErrorCode code = 0;
  PetscBool      pushed = PETSC_FALSE;
  PetscInt      *pi = NULL, *pj = NULL;
  pfem_ksp      *h = NULL;
  PC             pc;
  int64_t        k, nnz = ptr[n];

  *out = NULL;
  /* Indices past PetscInt's range would be narrowed without a word. */
  if (n > (int64_t)PFEM_INT_MAX || nnz > (int64_t)PFEM_INT_MAX) {
    if (msg && len)
      snprintf(msg, len,
               "the system (%lld rows, %lld entries) is past PETSc's integer range: "
               "configure PETSc with --with-64-bit-indices",
               (long long)n, (long long)nnz);
    return (int)PETSC_ERR_ARG_OUTOFRANGE;
  }
  TRY(PetscCalloc1(1, &h), "PetscCalloc1");
  TRY(PetscMalloc1(n + 1, &pi), "PetscMalloc1");
  TRY(PetscMalloc1(nnz > 0 ? nnz : 1, &pj), "PetscMalloc1");
  for (k = 0; k <= n; k++) pi[k] = (PetscInt)ptr[k];
  for (k = 0; k < nnz; k++) pj[k] = (PetscInt)idx[k];

  TRY(PetscOptionsCreate(&h->opts), "PetscOptionsCreate");
  if (options) TRY(PetscOptionsInsertString(h->opts, options), "PetscOptionsInsertString");
  TRY(PetscOptionsPush(h->opts), "PetscOptionsPush");
  pushed = PETSC_TRUE;

  TRY(MatCreate(PETSC_COMM_SELF, &h->K), "MatCreate");
  TRY(MatSetSizes(h->K, (PetscInt)n, (PetscInt)n, (PetscInt)n, (PetscInt)n), "MatSetSizes");
  TRY(MatSetType(h->K, MATSEQAIJ), "MatSetType");
  TRY(MatSeqAIJSetPreallocationCSR(h->K, pi, pj, val), "MatSeqAIJSetPreallocationCSR");
  TRY(VecCreateSeq(PETSC_COMM_SELF, (PetscInt)n, &h->vb), "VecCreateSeq");
  TRY(VecDuplicate(h->vb, &h->vy), "VecDuplicate");

  TRY(KSPCreate(PETSC_COMM_SELF, &h->ksp), "KSPCreate");
  TRY(KSPSetOptionsPrefix(h->ksp, "pfem_"), "KSPSetOptionsPrefix");
  TRY(KSPSetOperators(h->ksp, h->K, h->K), "KSPSetOperators");
  TRY(KSPGetPC(h->ksp, &pc), "KSPGetPC");
  if (nv < n) {
    TRY(ISCreateStride(PETSC_COMM_SELF, (PetscInt)nv, 0, 1, &h->isv), "ISCreateStride");
    TRY(ISCreateStride(PETSC_COMM_SELF, (PetscInt)(n - nv), (PetscInt)nv, 1, &h->isp),
        "ISCreateStride");
    if (bs > 1 && nv % bs == 0) TRY(ISSetBlockSize(h->isv, (PetscInt)bs), "ISSetBlockSize");
    TRY(PCSetType(pc, PCFIELDSPLIT), "PCSetType");
    TRY(PCFieldSplitSetIS(pc, "v", h->isv), "PCFieldSplitSetIS");
    TRY(PCFieldSplitSetIS(pc, "p", h->isp), "PCFieldSplitSetIS");
  }
  TRY(KSPSetFromOptions(h->ksp), "KSPSetFromOptions");
  TRY(KSPSetUp(h->ksp), "KSPSetUp");
  *out = h;
  h = NULL;

done:
  if (pushed) PetscOptionsPop();
  if (h) destroy(h);
  if (pi) PetscFree(pi);
  if (pj) PetscFree(pj);
  return (int)code;
}

/* Solves K y = b with a KSP of pfem_petsc_create; y holds the initial
 * guess (used when nonzero_guess) and the solution. *its and *reason are
 * KSP's iteration count and converged reason (negative: diverged).
 * Returns 0 or a PETSc error code (text in msg). */
int pfem_petsc_solve(pfem_ksp *h, const double *b, double *y, int nonzero_guess, int64_t *its,
                     int *reason, char *msg, size_t len)
{
  PetscErrorCode code = 0;
  PetscBool      pushed = PETSC_FALSE;
  PetscInt       n = 0, it = 0;
  PetscScalar   *a;
  KSPConvergedReason why = KSP_CONVERGED_ITERATING;

  *its = 0;
  *reason = 0;
  TRY(PetscOptionsPush(h->opts), "PetscOptionsPush");
  pushed = PETSC_TRUE;
  TRY(VecGetLocalSize(h->vb, &n), "VecGetLocalSize");
  TRY(VecGetArray(h->vb, &a), "VecGetArray");
  memcpy(a, b, (size_t)n * sizeof(double));
  TRY(VecRestoreArray(h->vb, &a), "VecRestoreArray");
  TRY(VecGetArray(h->vy, &a), "VecGetArray");
  if (nonzero_guess) memcpy(a, y, (size_t)n * sizeof(double));
  else memset(a, 0, (size_t)n * sizeof(double));
  TRY(VecRestoreArray(h->vy, &a), "VecRestoreArray");
  TRY(KSPSetInitialGuessNonzero(h->ksp, nonzero_guess ? PETSC_TRUE : PETSC_FALSE),
      "KSPSetInitialGuessNonzero");
  TRY(KSPSolve(h->ksp, h->vb, h->vy), "KSPSolve");
  TRY(KSPGetIterationNumber(h->ksp, &it), "KSPGetIterationNumber");
  TRY(KSPGetConvergedReason(h->ksp, &why), "KSPGetConvergedReason");
  TRY(VecGetArray(h->vy, &a), "VecGetArray");
  memcpy(y, a, (size_t)n * sizeof(double));
  TRY(VecRestoreArray(h->vy, &a), "VecRestoreArray");
  *its = (int64_t)it;
  *reason = (int)why;

done:
  if (pushed) PetscOptionsPop();
  return (int)code;
}
