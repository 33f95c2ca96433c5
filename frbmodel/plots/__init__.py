"""Figures: they take results and arrays and never compute physics."""
