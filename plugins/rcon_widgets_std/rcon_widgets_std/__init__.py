"""RCON Standard widgets: Button, Label, Text Field, Switch, Slider, Stepper, Text View, Compound."""
