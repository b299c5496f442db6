// qstrs of this port beyond those the sources name: none
