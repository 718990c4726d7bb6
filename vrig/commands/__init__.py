"""The pieces of the ``vrig`` command line (:mod:`vrig.cli`): its exit codes, what every
command shares (argument checks, the rig, the desired record), and the commands other than
``reconstruct``, one module each (its parser and its body).

``vrig reconstruct`` itself lives in :mod:`vrig.cli` and runs the library's job
(:mod:`vrig.job`); nothing in the library imports this package.

The protocol of a command module (written here once; its functions are the CLI's internals):
``_add_parser(sub, epilog)`` adds the command's parser to ``sub`` (the ``vrig`` parser's
``argparse`` subcommands), ``epilog`` being the exit-code table every ``--help`` ends with;
``_run(args) -> int`` runs the command on the parsed ``argparse.Namespace`` and returns its exit
code (:class:`~vrig.commands.exit_codes.ExitCode`). ``info`` has one ``_add_parsers`` and a
``_run_*`` per command; ``bench`` passes its raw arguments on (``_run(argv)``).
"""
