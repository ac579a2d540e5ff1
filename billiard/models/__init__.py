"""The physics between and at impacts: flight models, impact laws, impact locators, contact
phases and holds.
"""
