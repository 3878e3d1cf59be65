"""Exports: the results folder, VTU/PVD, renders and ParaView states."""
