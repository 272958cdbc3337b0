# gradvi — make targets. Everything needs only Rust (cargo) except `crosscheck` (installs
# python3-dolfinx and gmsh from Debian) and `meshes` (installs gmsh from Debian).
# The Cargo workspace: the library (Cargo.toml, src/), the command line (cli/, the `gradvi`
# binary) and the developer tools (devtools/, the `gradvi-dev` binary: benchmarks, regression
# check, fuzzer); one target directory for all.

CARGO ?= cargo
BIN := target/release/gradvi
DEV := target/release/gradvi-dev
FVCA5_MESHES ?=
PYTHON := /usr/bin/python3
REFDIR := replication/results/reference

.PHONY: all build test test-external test-solve3d fuzz determinism lint fmt doc replicate replicate-quick report meshes crosscheck crosscheck-coarse reference-deps bench bench-peers bench-peers3d bench-domains3d bench-hmm3d bench-amg bench-baseline clean

all: build

## build: the release binaries gradvi and gradvi-dev
build:
	$(CARGO) build --release --workspace

## test: the test suite of the workspace (library: unit, convergence and regression tiers;
## command line; developer tools), a few minutes at most
test:
	$(CARGO) test --workspace

## test-external: the tests that need what a fresh machine may lack or that take longer
## (#[ignore]d in `make test`): the FVCA5 files in ../shared/meshes/fvca5, HArDCore3D's files in
## ../shared/meshes/hardcore3d (3D patch tests and slopes of HMM, P1, CR: tests/convergence3d.rs),
## the larger 3D convergence levels and 3D obstacle problems (tests/obstacle3d.rs), and dolfinx
## (installed here if missing). CI runs it.
test-external: build reference-deps
	$(CARGO) test --workspace -- --ignored

## test-solve3d: the 3D solves of problems/*-3d.toml through the command line, with the
## Signorini example on gmsh tetrahedra (meshes/3d/signorini3d.geo; installs gmsh if missing)
test-solve3d: reference-deps
	$(CARGO) test -p gradvi-cli --test solve3d -- --include-ignored

## fuzz: seeded mutation fuzzing of meshes and problem files through the readers, validation
## and a small solve of the release gradvi, in child processes under memory and time limits
## (FUZZ_SECONDS, FUZZ_SEED); the fuzzer is gradvi-dev
FUZZ_SECONDS ?= 300
FUZZ_SEED ?= 1
fuzz: build
	$(DEV) fuzz --seconds $(FUZZ_SECONDS) --seed $(FUZZ_SEED) --gradvi $(BIN)

## determinism: the same solves (2D HMM and P1, 3D HMM, direct and iterative) in pools of 1, 2
## and 4 threads, compared bit for bit with their NITER (tests/determinism.rs, also part of
## `make test`)
determinism:
	$(CARGO) test --test determinism

## lint: formatting, clippy with warnings as errors (the workspace, then the library alone:
## nothing of the other members' dependencies), and documentation
lint:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets -- -D warnings
	$(CARGO) clippy -p gradvi --lib -- -D warnings
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --workspace --no-deps

fmt:
	$(CARGO) fmt --all

doc:
	$(CARGO) doc --workspace --no-deps

## replicate: every table and figure of the paper -> replication/REPORT.md, and beyond it the
## 3D convergence tables and figures -> replication/REPORT-3D.md
## (add FVCA5_MESHES=../shared/meshes/fvca5 to run Test 2 on the original files too)
replicate: build
	$(BIN) replicate $(if $(FVCA5_MESHES),--fvca5 $(FVCA5_MESHES),)

## replicate-quick: the same on the coarsest meshes only (3D: levels 1-2), into /tmp
replicate-quick: build
	$(BIN) replicate --quick --out /tmp/gradvi-replicate-quick

## report: rewrite REPORT.md and the CSV-based plots from the existing CSV files
report: build
	$(BIN) replicate --report-only

## meshes: regenerate meshes/*.msh from meshes/*.geo (installs gmsh if missing)
meshes:
	bash meshes/generate.sh

reference-deps:
	bash reference/install.sh

## crosscheck: dolfinx P1 reference solves on the same meshes, diffed -> replication/CROSSCHECK.md
## (Tests 1-3 on the 2D meshes; in 3D, problems/ex9-3d.toml on meshes/3d/ex9_3d_1,2.msh and
## problems/signorini-3d.toml on meshes/3d/signorini3d_1,2.msh, gmsh tetrahedra)
crosscheck: build reference-deps
	$(PYTHON) reference/solve.py --all --outdir $(REFDIR)
	$(BIN) crosscheck --reference $(REFDIR)

## crosscheck-coarse: the same on the coarsest meshes (run by CI; in 3D ex9_3d_1 and signorini3d_1)
crosscheck-coarse: build reference-deps
	$(PYTHON) reference/solve.py --coarse --outdir /tmp/gradvi-reference-coarse
	$(BIN) crosscheck --coarse --reference /tmp/gradvi-reference-coarse --out /tmp/gradvi-crosscheck-coarse

## bench: peer benchmark (PETSc ex9 side by side, any domain), then the scaling benchmark
##        (HMM and P1, Test 3, 1e3 to 1e6 cells; dolfinx up to ~300k cells)
##        -> replication/results/bench_peers.csv, bench.csv and replication/BENCHMARKS.md
##        (`$(DEV) bench --report-only` rewrites BENCHMARKS.md and REGRESSION.md from the CSVs)
bench: bench-peers build reference-deps
	$(DEV) bench

## bench-baseline: BASE=REV (default 73dd38a, the build the regression rows compare with)
##        builds revision REV in target/baseline (through a temporary git worktree in
##        target/baseline-src, which the workspace excludes, so that a revision from before the
##        workspace builds as a package of its own: its
##        gradvi-dev, or its gradvi for revisions before the workspace, whose gradvi has the
##        benchmark's child mode) and runs every gradvi case of the two benchmarks with both
##        builds, alternately, 3 times each (GRADVI_BENCH_REPEAT), comparing medians in the same
##        run; a case above 1.1x is measured again, 6 more runs of each (GRADVI_BENCH_CONFIRM),
##        and judged on all its runs; scaling cases: GRADVI_BENCH_VARIANTS (default nested),
##        GRADVI_BENCH_MAX_CELLS;
##        ex9 up to GRADVI_BENCH_EX9_MAX_GRID (default 1025)
##        -> replication/results/bench_baseline.csv and replication/REGRESSION.md
BASE ?= 73dd38a
bench-baseline: build
	rm -rf target/baseline-src && git worktree prune
	git worktree add --detach target/baseline-src $(BASE)
	bin=$$(test -f target/baseline-src/devtools/Cargo.toml && echo gradvi-dev || echo gradvi) && \
	$(CARGO) build --release --manifest-path target/baseline-src/Cargo.toml \
		--target-dir target/baseline --workspace --bin $$bin && \
	git worktree remove --force target/baseline-src && \
	$(DEV) bench --baseline target/baseline/release/$$bin --baseline-rev $(BASE)

## bench-amg: multigrid-preconditioned CG against sparse Cholesky on model problems (the
##        measurements behind linalg::amg's defaults; prints a table)
bench-amg:
	$(CARGO) bench --bench amg

## bench-peers: PETSc ex9 (installed and built from Debian's packages by benches/petsc/) next to
##        gradvi at equal unknowns and equal cores: 1 and N (the machine's cores), PETSc on 1
##        process and under mpiexec -n N (memory summed over the ranks), gradvi on 1 and N rayon
##        threads; every case also without the obstacle (its linear variant, for the cost ratio
##        R), so four runs per case; grids from GRADVI_BENCH_EX9_MIN_GRID (default 0) up to
##        GRADVI_BENCH_EX9_MAX_GRID (default 4097: the 4097² grid, PETSc and gradvi P1 only,
##        where 21 GiB are available; the rows of the grids not run are kept), and
##        the L-shape/disk/hole family (meshed by gmsh: reference-deps installs it);
##        GRADVI_BENCH_PEER_REPEAT=N runs every case N times, interleaved, keeping the median
##        (about N times as long); the same domains meshed again with another gmsh seed at
##        other sizes, default linear solver; GRADVI_BENCH_PEERS=ex9, =domains or =reseeded
##        (comma-separated) runs those parts
##        -> replication/results/bench_peers.csv, BENCHMARKS.md
bench-peers: build reference-deps
	$(DEV) bench --peers

## bench-peers3d: the 3D radial obstacle (problems/ex9-3d.toml) against dolfinx 0.5 (Debian's
##        python3-dolfinx, installed by reference-deps if missing, run with /usr/bin/python3:
##        benches/dolfinx/ex9_3d.py) on the same Kuhn tetrahedra of (-2,2)^3, n^3 cubes: gradvi
##        P1 (iterative) on 1 and N rayon threads, dolfinx SNES vinewtonrsls with CG + GAMG and
##        CG + hypre on 1 process and under mpiexec -n N (memory summed over the ranks); every
##        case also without the bounds (the cost ratio R); n from GRADVI_BENCH_3D_MIN_N (default
##        0) up to GRADVI_BENCH_3D_MAX_N (default 64: 275k unknowns, a few minutes; 200 adds
##        n = 100 and 200, about 1M and 8M unknowns; the rows of the sizes not run are kept;
##        GRADVI_BENCH_3D_DOLFINX=gamg runs that dolfinx configuration only); a
##        dolfinx case runs only if 1.05x its peak, extrapolated from its rows at smaller sizes,
##        fits in the memory available -> replication/results/bench_peers3d.csv, BENCHMARKS.md
bench-peers3d: build reference-deps
	$(DEV) bench --peers3d

## bench-domains3d: the 3D "any domain" family: problems/ex9-3d.toml (the radial obstacle, its
##        exact solution as Dirichlet data) on gmsh tetrahedra of benches/domains3d/*.geo (a
##        ball, the cube (-2,2)^3 with a spherical hole, the cube itself; reference-deps installs
##        gmsh) of about 1e4 to 1e6 cells, up to GRADVI_BENCH_DOMAINS3D_MAX_CELLS (default 1e6:
##        gmsh alone takes about a minute for it), HMM and P1; and HArDCore3D's Voronoi family
##        (../shared/meshes/hardcore3d/Voro-small-0 or GRADVI_BENCH_HARDCORE3D, HMM; "not run"
##        in the report where missing); default solver options (auto linear solver, nested
##        warm start), 1 and N rayon threads; GRADVI_BENCH_DOMAINS3D=ball,hole,cube,voronoi
##        selects domains (the others' rows are kept)
##        -> replication/results/bench_domains3d.csv, BENCHMARKS.md (growth exponents, target 6)
bench-domains3d: build reference-deps
	$(DEV) bench --domains3d

## bench-hmm3d: HMM on n^3 cubes of (-2,2)^3, problems/ex9-3d.toml (the radial obstacle), gradvi
##        alone (iterative solver, nested warm start), 1 and N rayon threads, each case and its
##        linear variant (no bounds: the cost ratio R) in its own process; n in 32, 64, 100,
##        128, 200 up to GRADVI_BENCH_HMM3D_MAX_N (default 64; 200 is target 5, 8M cells within
##        24 GiB), a size skipped when its estimated peak does not fit in the memory available;
##        the rows of the sizes not run are kept
##        -> replication/results/bench_hmm3d.csv, BENCHMARKS.md (the verdict of target 5)
bench-hmm3d: build
	$(DEV) bench --hmm3d

clean:
	$(CARGO) clean

## python-test: the Python package (python/: PyO3 + maturin). Creates python/.venv, installs
## maturin, numpy, meshio, pytest, matplotlib and gmsh from PyPI, builds and installs the package
## (`pip install ./python`, release build in python/target) and runs its pytest suite, which also
## runs python/examples/test3.py and gmsh_signorini.py. The comparison with the command line
## uses target/release/gradvi when it has been built (this target builds it first).
PYTHON3 ?= python3
PYVENV := python/.venv
.PHONY: python-test python-install python-examples
python-test: build python-install
	cd python && .venv/bin/pytest tests

## python-install: the venv python/.venv with the package and the tools of python-test
python-install:
	test -x $(PYVENV)/bin/python || $(PYTHON3) -m venv $(PYVENV)
	printf '*\n' > $(PYVENV)/.gitignore
	$(PYVENV)/bin/python -m pip install -q --upgrade pip
	$(PYVENV)/bin/python -m pip install -q maturin numpy meshio pytest matplotlib gmsh
	$(PYVENV)/bin/python -m pip install -q ./python

## python-examples: runs the examples of python/examples/ that the test suite does not
## (signorini3d.py: a 3D mesh from gmsh, a Signorini solve, the contact zone plotted with
## matplotlib), each writing its figure into a new temporary directory; fails if one fails
python-examples: python-install
	out=$$(mktemp -d) && $(PYVENV)/bin/python python/examples/signorini3d.py $$out/signorini3d.png \
		&& test -s $$out/signorini3d.png && echo "figures in $$out"
