"""Nonlinear least squares with CasADi/IPOPT: the competitor SCR is measured against."""

from symid.nlls.frf import IpoptFRF

__all__ = ["IpoptFRF"]
