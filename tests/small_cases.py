"""The small meshes the suite's cases share, as overrides: one home for each size."""

# pad_disc on hex8, a 3 x 36 x 1 disc and a 3 x 6 pad: the coarsest that keeps its squeal
PAD_DISC = ["parts.disc.mesh.divisions=[3,36,1]", "parts.pad.mesh.divisions=[3,6,1,1]",
            'parts.disc.mesh.element="hex8"', 'parts.pad.mesh.element="hex8"']

# a thinner disc and a longer pad: the API's and the benchmarks' quick runs
PAD_DISC_THIN = ["parts.disc.mesh.divisions=[2,36,1]", 'parts.disc.mesh.element="hex8"',
                 "parts.pad.mesh.divisions=[3,8,1,1]", 'parts.pad.mesh.element="hex8"']
