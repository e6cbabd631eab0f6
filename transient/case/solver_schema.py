"""The case file schema's solver table: schemes, steps, damping, the reduced model, the
factorizations and their quadrature."""
from .nodes import Table, Value

SOLVER = Table("solution settings", {
    "modes": Table("modal analysis", {
        "count": Value("int", "number of modes (when fmax is 0)", 20, minimum=1),
        "fmax": Value("float", "compute all modes up to this frequency (0: use count)", 0.0,
                      "Hz", minimum=0.0, maximum=1e150),  # (2 pi f)^2 finite; model.band
        "shift": Value("float", "shift of shift-invert Lanczos, below the first frequency; a "
                       "negative value keeps free parts' rigid modes solvable", -1.0, "Hz"),
        "tie": Value("choice", "how contact pairs enter the modes: penalty (springs of density "
                     "k on the pair's rule, bilateral), preload (the contact laws' tangents at "
                     "the preload under the constant loads: the linearization the reduced "
                     "model starts from) or exact (the gap held at zero on the rule's rows: "
                     "the limit k -> infinity, the paper's perfect bilateral contact)",
                     "penalty", choices=("penalty", "preload", "exact")),
    }, optional=True),
    "scheme": Value("choice", "time integration: explicit (central differences), implicit "
                    "(reduced or full model: Newmark average acceleration, iteration operator at "
                    "the preload factorized once, Newton with the exact contact tangent through "
                    "low-rank updates) or exponential "
                    "(reduced model: each mode's linear part, with the contact linearized at the "
                    "preload, integrated exactly; the contact remainder taken linear in time "
                    "over the step)", "explicit",
                    choices=("explicit", "implicit", "exponential")),
    "corrections": Value("int", "exponential: evaluations of the contact forces at the end of "
                         "each step after the one at the predicted state", 1, minimum=0,
                         maximum=5),
    "corrector": Value("choice", "exponential: a step ends at the state its forces were last "
                       "evaluated at (evaluated: robust on stiff penalties closing), or "
                       "propagates once more from them (propagated: with corrections = 0 one "
                       "contact pass per step, as accurate on smooth contact), or solves for "
                       "its end forces by Newton with the exact contact tangent (implicit: "
                       "stable where contact stiffens far beyond the preload's, a hard tap; "
                       "its cost grows with the points whose tangent moved, so it suits "
                       "sampled and coarse rules; corrections is then unused)", "evaluated",
                       choices=("evaluated", "propagated", "implicit")),
    "t_end": Value("float", "simulated time after the preload", 0.0, "s", minimum=0.0),
    "mass": Value("choice", "mass matrix of the transient: lumped (HRZ), consistent, or auto "
                  "(lumped for central differences on the full model, which need it diagonal; "
                  "consistent otherwise)", "auto",
                  choices=("auto", "lumped", "consistent")),
    "dt": Value("float", "time step (0: 0.9 times the critical step for explicit, "
                "1 / (20 reduction.fmax) for exponential)", 0.0, "s", minimum=0.0),
    "force_dt": Value("bool", "run explicit with dt above the critical step anyway", False),
    "chunk": Value("int", "steps per kernel call at most, 0 for about 0.2 s of the kernel "
                   "each and 2000 steps at least (output and checks between calls, at least "
                   "20 times a run; the results do not depend on it)", 0, minimum=0),
    "drift_tolerance": Value("float", "a step fails (see subdivision) where the energy "
                             "balance drifts by more than this fraction of the largest energy "
                             "the run holds (mechanical) or has exchanged (work in, "
                             "dissipated)", 0.05, open_min=0.0),
    "subdivision": Value("int", "halvings of a step that fails (energy balance past "
                         "drift_tolerance, a state not finite, Newton not converged): the run "
                         "goes back to the last row before the failure and on at half the "
                         "step (its rows at the same times), down to dt / 2^subdivision; past "
                         "that it stops (0: at the first failure, whatever gave dt)", 4,
                         minimum=0, maximum=20),
    "damping": Table("damping", {
        "modal": Value("float", "modal damping ratio of every mode (reduced model)", 0.0,
                       minimum=0.0),
        "residual": Value("float", "damping ratio added to the reduced vectors above "
                          "reduction.cutoff only (the quasi-static contact and load statics): "
                          "numerical, it leaves the basis' modes undamped", 0.0,
                          minimum=0.0),
        "alpha": Value("float", "Rayleigh mass-proportional coefficient", 0.0, "1/s",
                       minimum=0.0),
        "beta": Value("float", "Rayleigh stiffness-proportional coefficient", 0.0, "s",
                      minimum=0.0),
        "loss_frequency": Value("float", "where a run's viscous damping eta / omega K_m "
                                "equals the materials' loss factors (0: reduction.fmax, the "
                                "band's top: the modes below it are damped less than by the "
                                "cea's i eta K_m, never more, so a run errs towards squeal)",
                                0.0, "Hz", minimum=0.0, maximum=1e150),
    }, optional=True),
    "reduction": Table("reduced model: normal modes of the preloaded structure to a cutoff above "
                       "the band, plus static responses", {
        "enabled": Value("bool", "integrate a reduced model (false: the full model)", False),
        "method": Value("choice", "assembled: the basis of the whole model, one factorization "
                        "of every part with the contact's low-rank update; components: each "
                        "part reduced on its own (its modes to the cutoff, its responses to "
                        "its interface's contact loads and to the loads), coupled through the "
                        "contact rows in reduced coordinates; auto: chosen at load, assembled "
                        "where its setup's memory estimate fits limits.memory (every shipped "
                        "case), else components, and components where a part is cut in "
                        "pieces", "auto", choices=("assembled", "components", "auto")),
        "fmax": Value("float", "the band of the answer: the complex modes `transient cea` "
                      "reports, the contact stiffness a sampled rule reproduces, and the "
                      "exponential scheme's default step (20 steps a period) are to this "
                      "frequency", 16000.0, "Hz", open_min=0.0, maximum=1e150),  # as modes.fmax
        "cutoff": Value("float", "the basis' normal modes reach this frequency (0: 2 fmax); "
                        "friction couples the band's modes with those above it, whose "
                        "truncation moves the real parts of the band's complex modes", 0.0,
                        "Hz", minimum=0.0, maximum=1e150),  # as modes.fmax
        "statics": Value("bool", "add static responses to the contact point loads and the load "
                         "patterns", True),
        "statics_tolerance": Value("float", "keep the contact static shapes whose structural "
                                   "flexibility beyond the modes is at least this fraction of "
                                   "the contact law's at the preload (0: keep one per point)",
                                   1e-3, minimum=0.0),
        "mass_scaling_hz": Value("float", "give the basis' vectors above this frequency (the "
                                 "contact and load statics, up to MHz) the mass that brings "
                                 "them down to it, their static response unchanged: the step "
                                 "of the explicit correctors and central differences grows "
                                 "where the contact stiffens, at an error on the modes below "
                                 "fmax that `transient cea` measures (0: none; above the "
                                 "cutoff)", 0.0, "Hz", minimum=0.0),
    }, optional=True),
    "newton": Table("Newton iterations of the preload and of the implicit scheme", {
        "tolerance": Value("float", "relative residual of the Newton iterations", 1e-10,
                           open_min=0.0),
        "max_iter": Value("int", "iteration cap (non-convergence fails the step: "
                          "solver.subdivision)", 50, minimum=1),
    }, optional=True),
    "linear_solver": Value("choice", "sparse factorization: auto picks CHOLMOD if installed, "
                           "else PARDISO, else SuperLU", "auto",
                           choices=("auto", "cholmod", "pardiso", "superlu")),
    "quadrature": Table("quadrature degrees of the element matrices (0: element default)", {
        "stiffness": Value("int", "degree for K", 0, minimum=0),
        "mass": Value("int", "degree for M", 0, minimum=0),
    }, optional=True),
}, optional=True)
