"""The pieces of the ``vrig`` command line (:mod:`vrig.cli`): its exit codes, what every
command shares (argument checks, the rig, the desired record), and the commands other than
``reconstruct``, one module each (its parser and its body).

``vrig reconstruct`` itself lives in :mod:`vrig.cli` and runs the library's job
(:mod:`vrig.job`); nothing in the library imports this package.
"""
