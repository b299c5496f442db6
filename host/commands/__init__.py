"""Sub-commands of the ``dxboard`` command line, one module each (see ``host.cli``)."""
