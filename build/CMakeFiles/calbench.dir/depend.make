# Empty dependencies file for calbench.
# This may be replaced when dependencies are built.
